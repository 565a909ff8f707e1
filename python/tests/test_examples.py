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
