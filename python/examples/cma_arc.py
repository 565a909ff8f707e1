"""CMA-ES (the `cma` package) designs the paper's circular-arc beam on Amorph's cluster.

Each design is a fixed-length genome of N points × 6 numbers in [0, 1] (amorph.unit_genome);
CMA-ES minimizes the beam's RMS error (%) and every batch it asks is evaluated by the cluster's
workers, recorded in results/<name>/run.sqlite. Run it from the repository's root:

    python python/examples/cma_arc.py --evaluations 2000
"""

import argparse

import cma
import numpy as np

import amorph

# What a design that cannot be evaluated (empty, not reaching the free end) costs: worse than any
# RMS error a beam that spans can have.
FAILED = 1000.0


def optimize(cluster, points=12, evaluations=2000, seed=1, resolution="6x20x6"):
    """Runs CMA-ES for `evaluations`; returns (best RMS %, its genome)."""
    scene = cluster.scene
    es = cma.CMAEvolutionStrategy(
        np.full(points * 6, 0.5),
        0.3,
        # A first batch that all fails (no design reaches the free end) is flat, which would
        # end CMA-ES at once (tolfun, tolflatfitness): go on until the budget instead.
        {
            "bounds": [0.0, 1.0],
            "seed": seed,
            "maxfevals": evaluations,
            "tolfun": 0.0,
            "tolflatfitness": evaluations,
            "verbose": -9,
        },
    )
    best = (np.inf, None)
    while not es.stop():
        batch = es.ask()
        genomes = [amorph.unit_genome(scene, x) for x in batch]
        outcomes = cluster.evaluate(genomes, resolution)
        errors = [o.figure if o.ok else FAILED for o in outcomes]
        es.tell(batch, errors)
        i = int(np.argmin(errors))
        if errors[i] < best[0]:
            best = (errors[i], genomes[i])
    return best


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--points", type=int, default=12)
    parser.add_argument("--evaluations", type=int, default=2000)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--resolution", default="6x20x6")
    parser.add_argument("--local-workers", type=int, default=None)
    args = parser.parse_args()
    with amorph.Cluster(name="cma_arc", fresh=True, local_workers=args.local_workers) as cluster:
        rms, genome = optimize(cluster, args.points, args.evaluations, args.seed, args.resolution)
        print(f"CMA-ES: best RMS {rms:.4f} % after {cluster.evaluations} evaluations (paper 0.10 %)")
        genome.save(f"{cluster.store.parent}/best_genome.json")


if __name__ == "__main__":
    main()
