"""pymoo's NSGA-II trades the circular-arc beam's RMS error against its voxels on Amorph's cluster.

The same two objectives as configs/beam_pareto.toml, but the search is pymoo's: each design is a
fixed-length genome of N points × 6 numbers in [0, 1] (amorph.unit_genome), varied by pymoo's
SBX crossover and polynomial mutation, and each generation is one batch for the cluster's
workers, recorded in results/<name>/run.sqlite. Prints the front and its hypervolume against the
reference point (10 %, every voxel of the grid). Run it from the repository's root:

    python python/examples/pymoo_pareto.py --evaluations 6000
"""

import argparse

import numpy as np
from pymoo.algorithms.moo.nsga2 import NSGA2
from pymoo.core.problem import Problem
from pymoo.indicators.hv import HV
from pymoo.optimize import minimize

import amorph

# Where a design that cannot be evaluated lands: worse than the reference point in both.
FAILED_RMS = 1000.0


class ArcTradeOff(Problem):
    """(RMS error %, voxels) of a batch of unit-box vectors, evaluated by the cluster."""

    def __init__(self, cluster, points, resolution):
        super().__init__(n_var=points * 6, n_obj=2, xl=0.0, xu=1.0)
        self.cluster, self.resolution = cluster, resolution
        self.cells = int(np.prod([int(n) for n in resolution.split("x")]))

    def _evaluate(self, x, out, *args, **kwargs):
        genomes = [amorph.unit_genome(self.cluster.scene, row) for row in x]
        outcomes = self.cluster.evaluate(genomes, self.resolution)
        out["F"] = np.array([
            [o.figure, o.metrics["voxels"]] if o.ok else [FAILED_RMS, 2 * self.cells]
            for o in outcomes
        ])


def hypervolume(front, resolution):
    """The area `front` ((RMS %, voxels) rows) dominates up to (10 %, the grid's cells)."""
    cells = int(np.prod([int(n) for n in resolution.split("x")]))
    return float(HV(ref_point=np.array([10.0, float(cells)]))(np.asarray(front, dtype=float)))


def optimize(cluster, points=12, evaluations=6000, seed=1, resolution="6x20x6"):
    """Runs NSGA-II (population 50) for `evaluations`; returns its front, (RMS %, voxels) rows
    sorted by RMS, and the front's hypervolume."""
    problem = ArcTradeOff(cluster, points, resolution)
    result = minimize(problem, NSGA2(pop_size=50), ("n_evals", evaluations), seed=seed,
                      verbose=False)
    front = np.unique(np.atleast_2d(result.F), axis=0)
    front = front[front[:, 0] < FAILED_RMS]
    return front, hypervolume(front, resolution)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--points", type=int, default=12)
    parser.add_argument("--evaluations", type=int, default=6000)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--resolution", default="6x20x6")
    parser.add_argument("--local-workers", type=int, default=None)
    args = parser.parse_args()
    with amorph.Cluster(name="pymoo_pareto", fresh=True, local_workers=args.local_workers) as cluster:
        front, volume = optimize(cluster, args.points, args.evaluations, args.seed, args.resolution)
        print(f"pymoo NSGA-II: {len(front)} designs on the front after {cluster.evaluations} "
              f"evaluations, hypervolume {volume:.0f}")
        for rms, voxels in front:
            print(f"  RMS {rms:.4f} %  {voxels:.0f} voxels")


if __name__ == "__main__":
    main()
