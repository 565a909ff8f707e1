"""Genomes: JSON and numpy round trips, and bad input refused with an exception that says what."""

import json

import numpy as np
import pytest

import amorph
from conftest import COARSE, random_genome


def test_genome_round_trips_through_json_and_numpy(tmp_path):
    rng = np.random.default_rng(7)
    genome = random_genome(rng, points=25)
    array = genome.to_array()
    assert array.shape == (25, 6) and array.dtype == np.float64
    assert amorph.Genome(array) == genome
    assert amorph.Genome.from_json(genome.to_json()) == genome
    # JSON's numbers carry every bit of a float64 (serde_json's float round trip).
    again = amorph.Genome.from_json(genome.to_json()).to_array()
    assert np.array_equal(again, array)
    path = tmp_path / "g.json"
    genome.save(path)
    assert amorph.Genome.load(path) == genome
    # A results file holding a genome under "genome" reads as that genome.
    path.write_text(json.dumps({"fitness": -1.0, "genome": json.loads(genome.to_json())}))
    assert amorph.Genome.load(path) == genome
    assert len(genome) == 25


def test_the_array_columns_are_the_json_fields():
    array = np.array([[0.1, 0.2, 0.3, -0.5, 0.05, 1.0]])
    point = json.loads(amorph.Genome(array).to_json())["points"][0]
    assert point == {"position": [0.1, 0.2, 0.3], "density": -0.5, "falloff": 0.05, "material": 1}
    assert amorph.GENOME_COLUMNS == ["x", "y", "z", "density", "falloff", "material"]


@pytest.mark.parametrize(
    "array, words",
    [
        (np.zeros((3, 5)), "6 columns"),
        (np.zeros(6), "2 dimensions"),
        (np.zeros((2, 3, 6)), "2 dimensions"),
        (np.array([[0.5, 0.5, np.nan, 1.0, 0.1, 0.0]]), "point 0, z = NaN"),
        (np.array([[0.5, 0.5, 0.5, np.inf, 0.1, 0.0]]), "point 0, density = inf"),
        (np.array([[0.5, 0.5, 0.5, 1.0, 0.1, 0.5]]), "material = 0.5"),
        (np.array([[0.5, 0.5, 0.5, 1.0, 0.1, -1.0]]), "material = -1"),
        (np.array([[0.5, 0.5, 0.5, 1.0, 0.1, 300.0]]), "material = 300"),
        ([["a", 1, 2, 3, 4, 5]], "genome array"),
    ],
)
def test_a_bad_array_raises_naming_what_is_wrong(array, words):
    with pytest.raises(ValueError, match=words.replace("(", r"\(")):
        amorph.Genome(array)


def test_a_genome_the_scene_cannot_use_raises(scene):
    unknown_material = amorph.Genome([[0.5, 0.5, 0.5, 1.0, 0.1, 5]])
    with pytest.raises(ValueError, match="material 5 is unknown"):
        scene.evaluate(unknown_material, COARSE)
    outside = amorph.Genome([[1.5, 0.5, 0.5, 1.0, 0.1, 0]])
    with pytest.raises(ValueError, match="point 0"):
        scene.voxelize(outside, COARSE)
    with pytest.raises(ValueError, match="resolution"):
        scene.evaluate(amorph.Genome([[0.5, 0.5, 0.5, 1.0, 0.1, 0]]), "6x20")


def test_bad_json_raises_naming_the_field():
    with pytest.raises(ValueError, match=r"points\[0\].falloff is missing"):
        amorph.Genome.from_json('{"points": [{"position": [0, 0, 0], "density": 1, "material": 0}]}')
    with pytest.raises(ValueError, match="NaN"):
        amorph.Genome.from_json('{"points": [{"position": [0, 0, 0], "density": NaN}]}')


def test_a_missing_file_is_an_os_error(tmp_path):
    with pytest.raises(OSError, match="cannot read"):
        amorph.Genome.load(tmp_path / "absent.json")
