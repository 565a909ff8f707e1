"""Question: at equal evaluations on the circular arc (6x20x6, one resolution), which finds the
lowest RMS error: Amorph's own search (the quickstart's default), CMA-ES or pymoo's GA driving
Amorph's cluster (python/examples, 12 points × 6 numbers)?

Runs: seeds 1 to 5 for each, 2,000 evaluations each, two local workers. Rule: the median best RMS
of the five seeds ranks them; the report gives all three as they are.

Run from the repository's root, with the package and the examples' dependencies installed:

    python python/benches/optimizers.py --evaluations 2000 --seeds 5
"""

import argparse
import importlib.util
import os
import statistics
import tempfile
import time

import amorph

REPO = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
ONE_LEVEL = {"levels": [[6, 20, 6]], "latest_switch": []}


def example(name):
    path = os.path.join(REPO, "python", "examples", f"{name}.py")
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def amorph_search(seed, evaluations):
    summary = amorph.run(
        name=f"own_{seed}",
        seed=seed,
        resolution=ONE_LEVEL,
        budget={"evaluations": evaluations, "target_rms_percent": 1e-6},
        local_workers=2,
        fresh=True,
    )
    return summary["best_outcome"].figure, summary["evaluations"]


def driven(name):
    optimize = example(name).optimize

    def run(seed, evaluations):
        with amorph.Cluster(name=f"{name}_{seed}", local_workers=2, fresh=True) as cluster:
            rms, _ = optimize(cluster, 12, evaluations, seed=seed)
            return rms, cluster.evaluations

    return run


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--evaluations", type=int, default=2000)
    parser.add_argument("--seeds", type=int, default=5)
    args = parser.parse_args()
    methods = {
        "Amorph's search": amorph_search,
        "CMA-ES (cma)": driven("cma_arc"),
        "pymoo GA": driven("pymoo_arc"),
    }
    os.chdir(tempfile.mkdtemp())
    print(f"load average {os.getloadavg()[0]:.2f}")
    results = {m: [] for m in methods}
    for seed in range(1, args.seeds + 1):
        for method, run in methods.items():
            start = time.perf_counter()
            rms, evaluations = run(seed, args.evaluations)
            results[method].append(rms)
            print(f"seed {seed}, {method}: {rms:.4f} % after {evaluations} evaluations, {time.perf_counter() - start:.1f} s")
    print(f"load average {os.getloadavg()[0]:.2f}")
    for method, values in results.items():
        print(f"{method}: median {statistics.median(values):.4f} %, range {min(values):.4f} to {max(values):.4f} %")


if __name__ == "__main__":
    main()
