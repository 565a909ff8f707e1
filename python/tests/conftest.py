"""Shared fixtures: the repository's configs, the workspace's binaries, and genomes drawn at
random within a scene's limits."""

import os
import pathlib

import numpy as np
import pytest

import amorph

REPO = pathlib.Path(__file__).resolve().parents[2]
QUICKSTART = REPO / "configs" / "quickstart.toml"
# The scene of the circular-arc beam at the coarse level of its schedule.
COARSE = "6x20x6"


def binary(name: str) -> pathlib.Path:
    """A workspace binary: $AMORPH_BIN_DIR/name, else the newest of target/{debug,release}."""
    if "AMORPH_BIN_DIR" in os.environ:
        candidates = [pathlib.Path(os.environ["AMORPH_BIN_DIR"]) / name]
    else:
        candidates = [REPO / "target" / p / name for p in ("debug", "release")]
    found = [c for c in candidates if c.exists()]
    if not found:
        pytest.fail(f"{name} is not built: run `cargo build --bin {name}` (tests/all.sh does)")
    return max(found, key=lambda c: c.stat().st_mtime)


def random_genome(rng: np.random.Generator, points: int = 30) -> amorph.Genome:
    """A genome inside the default limits: positions in [0, 1], density in [-1, 1], falloff in
    [0.02, 0.4], material 0 or 1 (the beam's palette)."""
    array = np.column_stack(
        [
            rng.uniform(0.0, 1.0, (points, 3)),
            rng.uniform(-1.0, 1.0, points),
            rng.uniform(0.02, 0.4, points),
            rng.integers(0, 2, points),
        ]
    )
    return amorph.Genome(array)


def spanning_genomes(scene: amorph.Scene, count: int, seed: int) -> list:
    """`count` random genomes that the beam evaluates (they reach its free end), so that
    comparisons of outcomes compare fitnesses, not only failures."""
    rng = np.random.default_rng(seed)
    found = []
    while len(found) < count:
        genome = random_genome(rng)
        array = genome.to_array()
        array[:, 3] = np.abs(array[:, 3])  # positive density fills the workspace
        genome = amorph.Genome(array)
        if scene.evaluate(genome, COARSE).ok:
            found.append(genome)
    return found


@pytest.fixture(scope="session")
def scene() -> amorph.Scene:
    return amorph.Scene.from_file(QUICKSTART)


@pytest.fixture()
def in_tmp(tmp_path, monkeypatch):
    """Runs the test in a scratch folder, where runs write their results/."""
    monkeypatch.chdir(tmp_path)
    return tmp_path
