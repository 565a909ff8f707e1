"""Whole runs from Python: progress, the run store read back, stop and resume to the same bits."""

import json
import os
import signal
import subprocess
import sys
import textwrap

import numpy as np

import amorph

# A short quickstart at one resolution, so its best voxels are at 6x20x6.
SHORT = {
    "budget": {"evaluations": 400, "target_rms_percent": 0.0001},
    "resolution": {"levels": [[6, 20, 6]], "latest_switch": []},
    "local_workers": 2,
}


def short(name, **extra):
    return dict(SHORT, name=name, **extra)


def test_a_run_reports_each_epoch_and_its_store_reads_back(in_tmp):
    epochs, live = [], []

    def progress(epoch):
        epochs.append(epoch)
        # The store of the run going on, read while it writes: at least this epoch is in it.
        store = amorph.open_run("results/whole")
        live.append(len(store.evaluations) >= epoch["evaluations"] and len(store.epochs) >= epoch["epoch"])

    summary = amorph.run(progress=progress, **short("whole"))
    assert live and all(live)
    assert summary["stop"] == "evaluation_budget" and summary["evaluations"] == 400
    assert [e["epoch"] for e in epochs] == list(range(1, summary["epochs"] + 1))
    store = amorph.open_run("results/whole")
    assert len(store.evaluations) == 400
    assert list(store.epochs["epoch"]) == [e["epoch"] for e in epochs]
    assert list(store.epochs["evaluations"]) == [e["evaluations"] for e in epochs]
    # history.csv has one row per island and epoch, as the progress dicts do.
    with open("results/whole/history.csv") as f:
        assert len(f.readlines()) - 1 == sum(len(e["islands"]) for e in epochs)
    best = store.best
    assert best == summary["best_task"]
    assert store.genome(best) == summary["best_genome"]
    assert store.outcome(best) == summary["best_outcome"]
    assert store.evaluations.rows()[0]["task_id"] == 1


def test_voxelize_equals_the_runs_best_voxels(in_tmp):
    summary = amorph.run(**short("voxels"))
    with open("results/voxels/best_voxels.json") as f:
        saved = json.load(f)
    scene = amorph.open_run("results/voxels").scene
    voxels = scene.voxelize(summary["best_genome"], tuple(saved["dims"]))
    # best_voxels.json holds z layers, bottom up, each a list of y rows of x characters.
    for z, layer in enumerate(saved["layers_z_up"]):
        for y, row in enumerate(layer):
            for x, c in enumerate(row):
                assert voxels[x, y, z] == (-1 if c == "." else int(c, 16))
    assert (voxels >= 0).sum() > 0


def test_a_stopped_run_resumes_to_the_bits_of_an_uninterrupted_one(in_tmp):
    whole = amorph.run(**short("whole"))
    run = amorph.Run(**short("stopped"))
    next(run)
    run.stop()
    list(run)
    assert run.summary["stop"] == "shutdown"
    assert run.summary["evaluations"] < 400
    resumed = amorph.run(resume=True, **short("stopped"))
    assert resumed["evaluations"] == 400
    assert resumed["best_genome"] == whole["best_genome"]
    assert resumed["best_outcome"] == whole["best_outcome"]
    a, b = amorph.open_run("results/whole"), amorph.open_run("results/stopped")
    assert np.array_equal(a.evaluations["fitness"], b.evaluations["fitness"], equal_nan=True)
    assert a.evaluations["genome"] == b.evaluations["genome"]


def test_ctrl_c_stops_a_run_that_then_resumes(in_tmp):
    # Long enough that the signal comes mid-run on any machine.
    keys = short("interrupted", budget={"evaluations": 1000, "target_rms_percent": 0.0001})
    # An interactive Python turns SIGINT into KeyboardInterrupt; a child of a shell script that
    # runs in the background (as CI may) starts with SIGINT ignored, so the child asks for it.
    script = textwrap.dedent(
        f"""
        import signal
        signal.signal(signal.SIGINT, signal.default_int_handler)
        import amorph
        amorph.run(progress=lambda e: print("epoch", e["epoch"], flush=True), **{keys!r})
        """
    )
    child = subprocess.Popen(
        [sys.executable, "-c", script],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=dict(os.environ, PYTHONUNBUFFERED="1"),
    )
    assert child.stdout.readline().startswith("epoch 1")
    child.send_signal(signal.SIGINT)
    _, err = child.communicate(timeout=60)
    assert child.returncode != 0 and "KeyboardInterrupt" in err
    stored = len(amorph.open_run("results/interrupted").evaluations)
    assert 0 < stored < 1000
    resumed = amorph.run(resume=True, **keys)
    whole = amorph.run(**dict(keys, name="whole"))
    assert resumed["evaluations"] == whole["evaluations"] == 1000
    assert resumed["best_outcome"] == whole["best_outcome"]


def test_a_bad_override_names_the_key(in_tmp):
    import pytest

    with pytest.raises(ValueError, match="search.population"):
        amorph.run(name="bad", search={"population": 1})
    with pytest.raises(ValueError, match="budgte"):
        amorph.run(name="bad", budgte={"evaluations": 3})
