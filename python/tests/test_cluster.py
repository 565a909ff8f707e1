"""Ask and tell: an outside optimizer's batches evaluated by the cluster, in order and to the same
bits whoever evaluates them, and recorded in a run store."""

import subprocess

import numpy as np
import pytest

import amorph
from conftest import COARSE, binary, random_genome, spanning_genomes


def batch(scene, seed):
    rng = np.random.default_rng(seed)
    return spanning_genomes(scene, 6, seed) + [random_genome(rng) for _ in range(6)]


def test_one_or_two_local_workers_give_the_same_outcomes(scene, in_tmp):
    genomes = batch(scene, 21)
    expected = scene.evaluate_many(genomes, COARSE)
    results = []
    for workers in (1, 2):
        with amorph.Cluster(name=f"ask{workers}", local_workers=workers) as cluster:
            first = cluster.evaluate(genomes, COARSE)
            second = cluster.evaluate(genomes[:5], COARSE)
            assert cluster.evaluations == 17
        results.append((first, second))
    assert results[0] == results[1]
    assert results[0][0] == expected and results[0][1] == expected[:5]
    store = amorph.open_run("results/ask2")
    assert len(store.evaluations) == 17 and set(store.evaluations["purpose"]) == {"asked"}
    assert list(store.epochs["evaluations"]) == [12, 17]
    assert store.genome(3) == genomes[2]


def test_a_remote_worker_evaluates_the_batches(scene, in_tmp):
    genomes = batch(scene, 22)
    expected = scene.evaluate_many(genomes, COARSE)
    with amorph.Cluster(name="remote", local_workers=0, listen="127.0.0.1:0") as cluster:
        worker = subprocess.Popen(
            [binary("worker"), "--connect", cluster.url, "--threads", "2", "--name", "remote"],
            stderr=subprocess.PIPE,
        )
        try:
            assert cluster.evaluate(genomes, COARSE) == expected
        finally:
            cluster.close()
            worker.wait(timeout=60)
    workers = set(amorph.open_run("results/remote").evaluations["worker"])
    assert any("remote" in w for w in workers), workers


def test_a_cluster_resumes_from_its_store(scene, in_tmp):
    genomes = batch(scene, 23)
    with amorph.Cluster(name="again", local_workers=2) as cluster:
        first = cluster.evaluate(genomes, COARSE)
    with amorph.Cluster(name="again", local_workers=2, resume=True) as cluster:
        assert cluster.evaluate(genomes, COARSE) == first
        more = cluster.evaluate(genomes[:2], COARSE)
    assert more == first[:2]
    assert len(amorph.open_run("results/again").evaluations) == len(genomes) + 2
    with pytest.raises(RuntimeError, match="already exists"):
        amorph.Cluster(name="again")


def test_bad_batches_raise_naming_the_genome(scene, in_tmp):
    with amorph.Cluster(name="bad", local_workers=1) as cluster:
        nan = np.full((2, 6), 0.5)
        nan[:, 5] = 0
        nan[1, 3] = np.nan
        with pytest.raises(ValueError, match=r"genomes\[1\].*density = NaN"):
            cluster.evaluate([random_genome(np.random.default_rng(1)), nan], COARSE)
        with pytest.raises(ValueError, match=r"genomes\[0\].*material 4 is unknown"):
            cluster.evaluate([[[0.5, 0.5, 0.5, 1.0, 0.1, 4]]], COARSE)
        with pytest.raises(ValueError, match="resolution"):
            cluster.evaluate([random_genome(np.random.default_rng(1))], "0x1x1")
        assert cluster.evaluations == 0
    with pytest.raises(RuntimeError, match="closed"):
        cluster.evaluate([random_genome(np.random.default_rng(1))], COARSE)


def test_a_second_thread_is_refused_while_a_batch_runs(scene, in_tmp):
    import threading
    import time

    # Forty 12x40x12 beams on one worker take seconds; the checks below come 0.2 s in.
    genomes = spanning_genomes(scene, 8, seed=31) * 5
    with amorph.Cluster(name="threads", local_workers=1) as cluster:
        results = []
        asking = threading.Thread(target=lambda: results.append(cluster.evaluate(genomes, "12x40x12")))
        asking.start()
        time.sleep(0.2)
        # Neither waits for the batch (which would hold the GIL the batch's thread needs).
        assert cluster.evaluations == 0
        with pytest.raises(RuntimeError, match="one batch at a time"):
            cluster.evaluate(genomes[:1], COARSE)
        asking.join(timeout=300)
        assert len(results[0]) == 40 and cluster.evaluations == 40
