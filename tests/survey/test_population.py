"""Population files: the shipped ones load; a bad file names the file, key, value, allowed."""

from __future__ import annotations

import tomllib

import numpy as np
import pytest

from harness.scenarios.errors import ScenarioError
from harness.survey.population import (
    POPULATION_DIR,
    Distribution,
    load_population,
    parse_population,
    population_files,
    resolve_populations,
)

REQUIRED_FAMILIES = {"rod-ground", "box-corner", "polygon-corner", "spinning-disk", "disk-disk",
                     "disk-rod", "box-on-box-face"}

GOOD = """
name = "tiny"
restitution = 0.5
friction = { uniform = [0.0, 1.0] }
[ground]
[approach]
speed = 1.0
direction_deg = { uniform = [-30.0, 30.0] }
[[body]]
name = "box"
shape = "box"
width = 0.4
height = 0.2
mass = 1.0
angle_deg = { uniform = [10.0, 80.0] }
"""


def test_every_required_family_ships_and_loads():
    populations = {p.name: p for p in resolve_populations()}
    assert REQUIRED_FAMILIES <= set(populations)
    for path in population_files():
        assert load_population(path).name == path.stem  # file name = family name


def test_two_body_populations_declare_placement_and_ground_ones_do_not():
    for population in resolve_populations():
        assert (population.placement_deg is None) == population.ground
        assert len(population.bodies) == (1 if population.ground else 2)


@pytest.mark.parametrize("kind, values", [("uniform", (0.2, 0.7)), ("log_uniform", (0.1, 10.0))])
def test_continuous_draws_stay_in_bounds_and_spread(kind, values):
    rng = np.random.default_rng(3)
    draws = np.array([Distribution(kind, values).draw(rng) for _ in range(2000)])
    assert draws.min() >= values[0] and draws.max() <= values[1]
    # Log-uniform: half of the draws below the geometric mean (±5%, ~4.5 sigma at n = 2000).
    middle = (values[0] + values[1]) / 2 if kind == "uniform" else np.sqrt(values[0] * values[1])
    assert abs(np.mean(draws < middle) - 0.5) < 0.05


def test_choice_draws_only_the_choices():
    rng = np.random.default_rng(4)
    draws = {Distribution("choice", (3, 5, 8)).draw(rng) for _ in range(200)}
    assert draws == {3, 5, 8}


def _error(text: str, path="bad.toml") -> ScenarioError:
    with pytest.raises(ScenarioError) as caught:
        parse_population(tomllib.loads(text), path)
    return caught.value


def test_the_good_example_parses():
    population = parse_population(tomllib.loads(GOOD), "good.toml")
    assert population.ground and population.restitution == Distribution("fixed", (0.5,))


@pytest.mark.parametrize("old, new, key, words", [
    ('friction = { uniform = [0.0, 1.0] }', 'friction = { unifrom = [0.0, 1.0] }', "friction",
     "did you mean 'uniform'"),
    ('friction = { uniform = [0.0, 1.0] }', 'friction = { uniform = [1.0, 0.0] }',
     "friction.uniform", "low < high"),
    ("restitution = 0.5", "restitution = 1.5", "restitution", "allowed: 0 … 1"),
    ("width = 0.4", "width = -0.4", "body.box.width", "> 0"),
    ("width = 0.4", "widht = 0.4", "body.box.widht", "did you mean 'width'"),
    ("direction_deg = { uniform = [-30.0, 30.0] }", "direction_deg = { uniform = [-90.0, 30.0] }",
     "approach.direction_deg", "-90 < direction_deg < 90"),
    ('shape = "box"', 'shape = "boxx"', "body.box.shape", "did you mean 'box'"),
    ("[ground]", "mass_ratio = 2.0\n[ground]", "mass_ratio", "only for two free bodies"),
    ('name = "tiny"', 'name = "tiny"\ndescription = "a\\u0000b"', "description",
     "control character '\\x00' at offset 1"),
    ('name = "tiny"', 'name = "tiny"\ndescription = """two\nlines"""', "description",
     "control character '\\n' at offset 3"),
])
def test_a_bad_value_names_file_key_value_and_allowed(old, new, key, words):
    assert old in GOOD
    error = _error(GOOD.replace(old, new, 1))
    assert any(e.key == key and e.path == "bad.toml" for e in error.errors), str(error)
    assert words in str(error)


def test_a_bad_shape_is_the_one_error_of_its_body():
    """The box's own keys are not reported as unknown because its shape is misspelt."""
    error = _error(GOOD.replace('shape = "box"', 'shape = "sphere"', 1))
    assert [e.key for e in error.errors] == ["body.box.shape"], str(error)
    assert "disk, rod, box, polygon" in str(error)
    error = _error(GOOD.replace('shape = "box"', 'shape = "sphere"\ncolour = "red"', 1))
    assert sorted(e.key for e in error.errors) == ["body.box.colour", "body.box.shape"]


def test_every_problem_is_listed_at_once():
    text = GOOD.replace("restitution = 0.5", "restitution = 2.0").replace("width = 0.4",
                                                                          "width = 0")
    error = _error(text)
    assert {e.key for e in error.errors} >= {"restitution", "body.box.width"}


def test_polygon_sides_must_be_integers():
    text = GOOD.replace('shape = "box"\nwidth = 0.4\nheight = 0.2',
                        'shape = "polygon"\nsides = 4.5\ncircumradius = 0.2')
    error = _error(text)
    assert any(e.key == "body.box.sides" for e in error.errors), str(error)


def test_second_body_mass_comes_from_the_ratio_only():
    text = (POPULATION_DIR / "disk-disk.toml").read_text()
    text = text.replace('name = "b"\nshape = "disk"', 'name = "b"\nshape = "disk"\nmass = 1.0')
    error = _error(text)
    assert any(e.key == "body.b.mass" for e in error.errors), str(error)


def test_unknown_population_name_suggests_the_closest():
    with pytest.raises(ScenarioError, match="did you mean 'disk-rod'"):
        resolve_populations(["disk-rdo"])
