"""What a Python call costs over the Rust call it makes, and how evaluate_many scales.

1. `Scene.evaluate` from Python against the same evaluation timed inside Rust
   (`cargo bench -p amorph-python --bench evaluate_call`, which prints seconds per call), on a
   6x20x6 circular-arc beam, alternating the two in rounds so that the machine's load falls on
   both alike.
2. `Scene.evaluate_many` of 64 genomes on 1, 2, ... threads.

Run from the repository's root, with the package installed (pip install ./python):

    taskset -c 1 python python/benches/overhead.py --rounds 20 --calls 100

(taskset keeps both on one core, out of the way of the scheduler's moves.)
"""

import argparse
import os
import subprocess
import sys
import tempfile
import time

import numpy as np

import amorph

REPO = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
RESOLUTION = "6x20x6"


def genome(scene):
    """The benchmark's design: a spanning random genome, the same every time."""
    return spanning(scene, 1)


def spanning(scene, seed):
    """A random genome of positive density that the beam evaluates."""
    rng = np.random.default_rng(seed)
    while True:
        a = amorph.unit_genome(scene, rng.uniform(size=30 * 6)).to_array()
        a[:, 3] = np.abs(a[:, 3])
        g = amorph.Genome(a)
        if scene.evaluate(g, RESOLUTION).ok:
            return g


def python_seconds(scene, g, calls):
    scene.evaluate(g, RESOLUTION)
    start = time.perf_counter()
    for _ in range(calls):
        scene.evaluate(g, RESOLUTION)
    return (time.perf_counter() - start) / calls


def rust_seconds(path, calls):
    out = subprocess.run(
        ["cargo", "bench", "-q", "-p", "amorph-python", "--bench", "evaluate_call", "--",
         path, RESOLUTION, str(calls)],
        cwd=REPO, check=True, capture_output=True, text=True,
    ).stdout
    return float(out.split()[0])


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=20)
    parser.add_argument("--calls", type=int, default=100)
    args = parser.parse_args()
    scene = amorph.Scene.from_file(os.path.join(REPO, "configs", "quickstart.toml"))
    g = genome(scene)
    with tempfile.TemporaryDirectory() as d:
        path = os.path.join(d, "genome.json")
        g.save(path)
        rust_seconds(path, 10)  # builds the bench once, outside the timing
        print(f"load average {os.getloadavg()[0]:.2f}")
        ratios = []
        for r in range(args.rounds):
            # Alternate which goes first, so a drift in the machine's load favours neither.
            if r % 2:
                py = python_seconds(scene, g, args.calls)
                rust = rust_seconds(path, args.calls)
            else:
                rust = rust_seconds(path, args.calls)
                py = python_seconds(scene, g, args.calls)
            ratios.append(py / rust)
            print(f"round {r + 1}: rust {rust * 1e3:.3f} ms, python {py * 1e3:.3f} ms, ratio {py / rust:.4f}")
        print(f"python / rust: median {np.median(ratios):.4f}, range {min(ratios):.4f} to {max(ratios):.4f}")
    # Spanning designs, so that every evaluation runs the solver, as a search's mostly do.
    many = [spanning(scene, seed) for seed in range(64)]
    counts = list(range(1, len(os.sched_getaffinity(0)) + 1))
    seconds = {n: [] for n in counts}
    for _ in range(3):
        for n in counts:
            start = time.perf_counter()
            scene.evaluate_many(many, RESOLUTION, threads=n)
            seconds[n].append(time.perf_counter() - start)
    one = np.median(seconds[1])
    for n in counts:
        t = np.median(seconds[n])
        print(f"evaluate_many, 64 genomes, {n} threads: {t:.3f} s (median of 3), speed-up {one / t:.2f}")
    print(f"load average {os.getloadavg()[0]:.2f}")
    sys.stdout.flush()


if __name__ == "__main__":
    main()
