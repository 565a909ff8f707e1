"""pymoo's genetic algorithm designs the paper's circular-arc beam on Amorph's cluster.

Each design is a fixed-length genome of N points × 6 numbers in [0, 1] (amorph.unit_genome);
the GA minimizes the beam's RMS error (%) and each generation is one batch for the cluster's
workers, recorded in results/<name>/run.sqlite. Run it from the repository's root:

    python python/examples/pymoo_arc.py --evaluations 2000
"""

import argparse

import numpy as np
from pymoo.algorithms.soo.nonconvex.ga import GA
from pymoo.core.problem import Problem
from pymoo.optimize import minimize

import amorph

# What a design that cannot be evaluated (empty, not reaching the free end) costs: worse than any
# RMS error a beam that spans can have.
FAILED = 1000.0


class ArcBeam(Problem):
    """The beam's RMS error (%) of a batch of unit-box vectors, evaluated by the cluster."""

    def __init__(self, cluster, points, resolution):
        super().__init__(n_var=points * 6, n_obj=1, xl=0.0, xu=1.0)
        self.cluster, self.resolution = cluster, resolution

    def _evaluate(self, x, out, *args, **kwargs):
        genomes = [amorph.unit_genome(self.cluster.scene, row) for row in x]
        outcomes = self.cluster.evaluate(genomes, self.resolution)
        out["F"] = np.array([o.figure if o.ok else FAILED for o in outcomes])


def optimize(cluster, points=12, evaluations=2000, seed=1, resolution="6x20x6"):
    """Runs the GA (population 50) for `evaluations`; returns (best RMS %, its genome)."""
    problem = ArcBeam(cluster, points, resolution)
    result = minimize(problem, GA(pop_size=50), ("n_evals", evaluations), seed=seed, verbose=False)
    return float(result.F[0]), amorph.unit_genome(cluster.scene, result.X)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--points", type=int, default=12)
    parser.add_argument("--evaluations", type=int, default=2000)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--resolution", default="6x20x6")
    parser.add_argument("--local-workers", type=int, default=None)
    args = parser.parse_args()
    with amorph.Cluster(name="pymoo_arc", fresh=True, local_workers=args.local_workers) as cluster:
        rms, genome = optimize(cluster, args.points, args.evaluations, args.seed, args.resolution)
        print(f"pymoo GA: best RMS {rms:.4f} % after {cluster.evaluations} evaluations (paper 0.10 %)")
        genome.save(f"{cluster.store.parent}/best_genome.json")


if __name__ == "__main__":
    main()
