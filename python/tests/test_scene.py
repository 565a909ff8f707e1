"""Scenes: built three ways, and evaluation that gives the same bits as `worker evaluate`."""

import json
import subprocess

import numpy as np
import pytest

import amorph
from conftest import COARSE, QUICKSTART, binary, random_genome, spanning_genomes


def test_evaluate_gives_the_bits_of_worker_evaluate(scene, tmp_path):
    worker = binary("worker")
    genomes = spanning_genomes(scene, 3, seed=11)
    # A design that fails too: its typed failure must match the worker's.
    genomes.append(amorph.Genome([[0.5, 0.05, 0.5, 1.0, 0.03, 0]]))
    for i, genome in enumerate(genomes):
        path = tmp_path / f"g{i}.json"
        genome.save(path)
        printed = subprocess.run(
            [worker, "evaluate", "--genome", path, "--scene", QUICKSTART, "--resolution", COARSE],
            check=True,
            capture_output=True,
            text=True,
        ).stdout
        outcome = scene.evaluate(genome, COARSE)
        assert json.loads(outcome.to_json()) == json.loads(printed)
        assert amorph.Outcome.from_json(printed, scene) == outcome
    assert scene.evaluate(genomes[-1], COARSE).failure.kind in ("empty", "not_spanning")


def test_an_outcome_carries_fitness_figure_and_metrics(scene):
    genome = spanning_genomes(scene, 1, seed=3)[0]
    outcome = scene.evaluate(genome, COARSE)
    assert outcome.ok and outcome.failure is None
    metrics = outcome.metrics
    # The beam's figure is its RMS error in %, one of its metrics.
    assert outcome.figure == metrics["rms_percent"]
    assert sum(metrics["material_counts"]) == metrics["voxels"]
    as_dict = outcome.to_dict()
    assert as_dict["fitness"] == outcome.fitness and as_dict["failure"] is None


def test_evaluate_many_equals_evaluate_for_any_thread_count(scene):
    genomes = spanning_genomes(scene, 4, seed=5)
    genomes += [random_genome(np.random.default_rng(s)) for s in range(4)]
    one_by_one = [scene.evaluate(g, COARSE) for g in genomes]
    for threads in (1, 2, 3):
        assert scene.evaluate_many(genomes, COARSE, threads=threads) == one_by_one
    assert scene.evaluate_many([], COARSE) == []
    # Threads that share one simulation give the same bits too.
    assert scene.evaluate(genomes[0], COARSE, threads=2) == one_by_one[0]


def test_evaluate_many_names_the_bad_genome(scene):
    good = spanning_genomes(scene, 1, seed=5)[0]
    bad = amorph.Genome([[0.5, 0.5, 0.5, 1.0, 0.1, 9]])
    with pytest.raises(ValueError, match=r"genomes\[1\]"):
        scene.evaluate_many([good, bad], COARSE)
    with pytest.raises(ValueError, match="threads"):
        scene.evaluate_many([good], COARSE, threads=0)


def test_a_scene_from_keywords_toml_or_file_is_the_same(scene):
    from_keywords = amorph.Scene(kind="beam", target="circular_arc")
    from_text = amorph.Scene.from_toml(QUICKSTART.read_text())
    genome = spanning_genomes(scene, 1, seed=9)[0]
    expected = scene.evaluate(genome, COARSE)
    assert from_keywords.evaluate(genome, COARSE) == expected
    assert from_text.evaluate(genome, COARSE) == expected
    assert amorph.Scene.from_toml(scene.to_toml()).evaluate(genome, COARSE) == expected
    assert scene.kind == "beam" and scene.materials == ["hard resin", "soft resin"]


@pytest.mark.parametrize(
    "keys, words",
    [
        ({"kind": "beam", "targte": "circular_arc"}, "unknown field `targte`"),
        ({"kind": "beam", "target": "spiral"}, "spiral"),
        ({"kind": "bridge"}, "bridge"),
        ({"kind": "beam", "target": "circular_arc", "tip_load": object()}, "scene.tip_load"),
    ],
)
def test_a_bad_scene_raises_naming_the_key(keys, words):
    with pytest.raises(ValueError, match=words):
        amorph.Scene(**keys)


def test_bad_toml_names_its_line():
    with pytest.raises(ValueError, match="line 3"):
        amorph.Scene.from_toml('[scene]\nkind = "beam"\ntarget = circular_arc\n')


def test_export_writes_the_fabrication_files(scene, tmp_path):
    genome = spanning_genomes(scene, 1, seed=2)[0]
    files = scene.export(genome, COARSE, tmp_path / "out")
    names = {p.name for p in files}
    assert {"design.3mf", "design.vxa", "profile.png"} <= names
    assert all(p.exists() and p.stat().st_size > 0 for p in files)
