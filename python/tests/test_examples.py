"""The two example optimizers drive the cluster and find better beams than chance does.

Each must beat random search at the same budget: the best of as many random unit-box genomes,
evaluated by the same scene. An optimizer that is miswired (maximizing the error, ignoring the
outcomes, scrambling the batch's order) does no better than chance and fails."""

import importlib.util
import pathlib

import numpy as np
import pytest

import amorph

EXAMPLES = pathlib.Path(__file__).resolve().parents[1] / "examples"
BUDGET = 1000
POINTS = 12


def example(name):
    spec = importlib.util.spec_from_file_location(name, EXAMPLES / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def random_search(scene, evaluations, seed):
    rng = np.random.default_rng(seed)
    genomes = [amorph.unit_genome(scene, rng.uniform(size=POINTS * 6)) for _ in range(evaluations)]
    outcomes = scene.evaluate_many(genomes, "6x20x6")
    return min(o.figure for o in outcomes if o.ok)


@pytest.mark.parametrize("name", ["cma_arc", "pymoo_arc"])
def test_the_example_beats_random_search_at_equal_budget(name, scene, in_tmp):
    with amorph.Cluster(name=name, local_workers=2) as cluster:
        rms, genome = example(name).optimize(cluster, POINTS, BUDGET, seed=1)
        asked = cluster.evaluations
    assert BUDGET <= asked < BUDGET + 100
    assert scene.evaluate(genome, "6x20x6").figure == pytest.approx(rms, rel=1e-12)
    chance = random_search(scene, asked, seed=1)
    assert rms < chance, f"{name}: {rms:.3f} % is no better than random search's {chance:.3f} %"


def test_the_pareto_example_keeps_a_front_better_than_random_search(scene, in_tmp):
    """pymoo's NSGA-II on (RMS error, voxels): its front dominates more of the objective space
    than the front of as many random designs, and every point of it is a design the scene
    evaluates to that very RMS error and voxel count."""
    pareto = example("pymoo_pareto")
    with amorph.Cluster(name="pymoo_pareto", local_workers=2) as cluster:
        front, volume = pareto.optimize(cluster, POINTS, BUDGET, seed=1)
        asked = cluster.evaluations
        store = cluster.store
    assert BUDGET <= asked < BUDGET + 100
    # A front: no point dominates another.
    for a in front:
        assert not any((b <= a).all() and (b < a).any() for b in front)
    # Every point is one the run evaluated.
    run = amorph.open_run(store)
    evaluated = {
        (o.figure, o.metrics["voxels"]) for o in (run.outcome(t) for t in run.evaluations["task_id"])
        if o.ok
    }
    assert all((rms, voxels) in evaluated for rms, voxels in front)
    rng = np.random.default_rng(1)
    genomes = [amorph.unit_genome(scene, rng.uniform(size=POINTS * 6)) for _ in range(asked)]
    chance = [[o.figure, o.metrics["voxels"]] for o in scene.evaluate_many(genomes, "6x20x6") if o.ok]
    chance_volume = pareto.hypervolume(chance, "6x20x6")
    assert volume > chance_volume, f"front {volume:.0f} is no better than random search's {chance_volume:.0f}"
