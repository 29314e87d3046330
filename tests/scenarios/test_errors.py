"""Bad scenario files: each problem gives an error naming the file, the key, the value and
what is allowed."""

from __future__ import annotations

import pytest

from harness.scenarios import ScenarioError, load_scenario, load_scenarios

GROUND = """\
name = "probe"
description = "a disk on the ground"
tags = ["quick"]
restitution = 0.5
friction = 0.3

[ground]

[[body]]
name = "disk"
shape = "disk"
radius = 0.1
mass = 1.0
velocity = [1.0, -1.0]
"""

TWO_BODY = """\
name = "pair"
restitution = 0.5
friction = 0.3

[[body]]
name = "a"
shape = "disk"
radius = 0.1
mass = 1.0
position = [0.0, 0.0]

[[body]]
name = "b"
shape = "disk"
radius = 0.1
mass = 1.0
position = [0.0, 0.2]
velocity = [0.0, -1.0]
"""

SLED = """\
name = "sled"
system = "two-sled"
restitution = 0.8
friction = 0.3

[parameters]
gamma = 0.2
delta = 0.85
"""


def write(tmp_path, text, name="bad.toml"):
    path = tmp_path / name
    path.write_text(text)
    return path


def error_of(tmp_path, text, name="bad.toml") -> ScenarioError:
    path = write(tmp_path, text, name)
    with pytest.raises(ScenarioError) as info:
        load_scenario(path)
    return info.value


def assert_names(error: ScenarioError, *parts: str) -> None:
    message = str(error)
    for part in parts:
        assert part in message, f"{part!r} not in {message!r}"


@pytest.mark.parametrize("shape", ['"sphere"', "3"])
def test_a_bad_shape_is_the_one_error_of_its_body(tmp_path, shape):
    """The rod's own keys are not reported as unknown because its shape is misspelt."""
    text = GROUND.replace('shape = "disk"\nradius = 0.1',
                          f"shape = {shape}\nlength = 1.0\nradius = 0.005")
    error = error_of(tmp_path, text)
    assert [e.key for e in error.errors] == ["body.disk.shape"], str(error)
    assert_names(error, "disk, rod, box, polygon")


def test_a_bad_shape_still_reports_a_key_no_shape_has(tmp_path):
    text = GROUND.replace('shape = "disk"', 'shape = "sphere"\ncolour = "red"')
    error = error_of(tmp_path, text)
    assert sorted(e.key for e in error.errors) == ["body.disk.colour", "body.disk.shape"]


def test_the_base_files_are_good(tmp_path):
    assert load_scenario(write(tmp_path, GROUND, "g.toml")).name == "probe"
    assert load_scenario(write(tmp_path, TWO_BODY, "t.toml")).name == "pair"
    assert load_scenario(write(tmp_path, SLED, "s.toml")).name == "sled"


@pytest.mark.parametrize(
    "old, new, parts",
    [
        # wrong type
        ("mass = 1.0", 'mass = "heavy"', ["body.disk.mass", "'heavy'", "must be a number",
                                          "a finite number"]),
        ("velocity = [1.0, -1.0]", "velocity = 1.0", ["body.disk.velocity", "1.0",
                                                      "list of 2 numbers"]),
        ('tags = ["quick"]', 'tags = "quick"', ["tags", "'quick'", "list of strings"]),
        # unknown keys, with the allowed ones and a suggestion
        ("friction = 0.3", "friction = 0.3\nfriciton = 0.3",
         ["friciton", "unknown key", "did you mean 'friction'", "restitution, friction"]),
        ("radius = 0.1", "radius = 0.1\nwidth = 0.2",
         ["body.disk.width", "unknown key in a disk body", "radius"]),
        # missing keys
        ("friction = 0.3\n", "", ["friction", "missing required key"]),
        ("radius = 0.1\n", "", ["body.disk.radius", "missing required key"]),
        # bad shape
        ('shape = "disk"', 'shape = "sphere"', ["body.disk.shape", "'sphere'",
                                                 "disk, rod, box, polygon"]),
        ('shape = "disk"', 'shape = "dsk"', ["did you mean 'disk'"]),
        ("radius = 0.1", "radius = -0.1", ["body.disk.radius", "-0.1", "> 0"]),
        # negative mass, e and mu out of range
        ("mass = 1.0", "mass = -2.0", ["body.disk.mass", "-2.0", "> 0"]),
        ("restitution = 0.5", "restitution = 1.5", ["restitution", "1.5", "0 … 1"]),
        ("friction = 0.3", "friction = -0.1", ["friction", "-0.1", ">= 0"]),
        ("restitution = 0.5", "restitution = nan", ["restitution", "nan", "finite"]),
        # not approaching, not touching (explicit position), derived tag, bad name
        ("velocity = [1.0, -1.0]", "velocity = [1.0, 1.0]",
         ["body.disk.velocity = [1.0, 1.0]:", "do not approach", "v_n < 0"]),
        ("velocity = [1.0, -1.0]", "velocity = [1.0, -1.0]\nposition = [0.0, 0.3]",
         ["body.disk.position", "[0.0, 0.3]", "must touch", "0.2 m", "gap_tolerance"]),
        ('tags = ["quick"]', 'tags = ["all"]', ["tags", "derived"]),
        ('name = "probe"', 'name = "a probe"', ["name", "'a probe'", "not a valid name"]),
        ('[ground]', '[ground]\nlevel = 0.0', ["ground.level", "unknown key"]),
        ('name = "probe"', 'name = "probe"\nengines = ["pymunk", "bullet3"]',
         ["engines", "bullet3", "pymunk, pybullet, mujoco, box2d"]),
        ('name = "probe"', 'name = "probe"\nlaws = ["poison"]',
         ["laws", "poison", "did you mean 'poisson'"]),
        # a description is one line of text: no NUL, newline or other control character
        ('description = "a disk on the ground"', 'description = "a disk\\u0000"',
         ["description", "'a disk\\x00'", "control character '\\x00' at offset 6",
          "no NUL, newline or tab"]),
        ('description = "a disk on the ground"', 'description = """a disk\non the ground"""',
         ["description", "control character '\\n' at offset 6"]),
        ('description = "a disk on the ground"', 'description = "a disk\\u001b[31m"',
         ["description", "control character '\\x1b'"]),
    ],
)
def test_ground_file_errors(tmp_path, old, new, parts):
    assert old in GROUND
    error = error_of(tmp_path, GROUND.replace(old, new, 1))
    assert_names(error, "bad.toml", *parts)


def test_a_file_with_several_errors_lists_them_all(tmp_path):
    text = GROUND.replace("mass = 1.0", "mass = -1.0").replace("restitution = 0.5",
                                                                 "restitution = 2")
    error = error_of(tmp_path, text)
    assert len(error.errors) == 2
    assert_names(error, "2 errors", "body.disk.mass", "restitution")
    assert all(e.path.endswith("bad.toml") for e in error.errors)


def test_error_attributes(tmp_path):
    error = error_of(tmp_path, GROUND.replace("mass = 1.0", "mass = -2.0"))
    assert (error.key, error.value, error.allowed) == ("body.disk.mass", -2.0, "> 0")
    assert isinstance(error, ValueError)


def test_toml_syntax_error_names_the_file(tmp_path):
    error = error_of(tmp_path, GROUND + "\nthis is not toml\n")
    assert_names(error, "bad.toml", "not valid TOML", "line")


def test_missing_file(tmp_path):
    with pytest.raises(ScenarioError, match="nothere.toml.*cannot read"):
        load_scenario(tmp_path / "nothere.toml")


# --------------------------------------------------------------------------------------------
# Shapes and poses
# --------------------------------------------------------------------------------------------
def test_flat_face_on_the_ground_is_outside_one_point_theory(tmp_path):
    text = GROUND.replace('shape = "disk"\nradius = 0.1',
                          'shape = "box"\nwidth = 0.2\nheight = 0.1')
    error = error_of(tmp_path, text)
    assert_names(error, "bad.toml", "body.disk.angle_deg", "2 contact points",
                 "outside one-point", "turn the body")
    text = text.replace("mass = 1.0", "mass = 1.0\nangle_deg = 30.0")
    assert load_scenario(write(tmp_path, text, "ok.toml")).bodies[0].shape.kind == "box"


def test_nearly_flat_face_is_flagged_too(tmp_path):
    """A second corner within ONE_POINT_TOLERANCE (0.1 mm) counts as a second point."""
    text = GROUND.replace('shape = "disk"\nradius = 0.1',
                          'shape = "rod"\nlength = 1.0\nradius = 0.01\nangle_deg = 0.001')
    assert_names(error_of(tmp_path, text), "2 contact points")


@pytest.mark.parametrize("vertices, problem", [
    ("[[0.0, 0.1], [0.1, -0.05], [-0.1, -0.05]]", "clockwise"),
    ("[[0.0, 0.0], [0.1, 0.0], [0.05, 0.02], [0.1, 0.1], [0.0, 0.1]]", "not strictly convex"),
    ("[[0.0, 0.0], [0.1, 0.0]]", "list of [x, y] pairs"),
])
def test_bad_polygons(tmp_path, vertices, problem):
    text = GROUND.replace('shape = "disk"\nradius = 0.1',
                          f'shape = "polygon"\nvertices = {vertices}\nangle_deg = 20.0')
    assert_names(error_of(tmp_path, text), "bad.toml", "body.disk.vertices", problem,
                 "counter-clockwise")


def test_polygon_vertices_are_centred_on_the_centroid(tmp_path):
    text = GROUND.replace('shape = "disk"\nradius = 0.1',
                          'shape = "polygon"\nvertices = [[0.0, 0.0], [0.3, 0.0], [0.0, 0.3]]\n'
                          "angle_deg = 20.0")
    shape = load_scenario(write(tmp_path, text, "ok.toml")).bodies[0].shape
    # The centroid of the shifted triangle is the origin; a few roundings: 1e-15 m.
    assert abs(shape.centroid()).max() < 1e-15
    assert shape.points[0] == pytest.approx((-0.1, -0.1))


# --------------------------------------------------------------------------------------------
# Two bodies
# --------------------------------------------------------------------------------------------
def test_two_bodies_must_touch(tmp_path):
    error = error_of(tmp_path, TWO_BODY.replace("position = [0.0, 0.2]", "position = [0.0, 0.25]"))
    assert_names(error, "bad.toml", "body.b.position", "[0.0, 0.25]", "must touch",
                 "gap 0.05 m (apart)", "1e-06 m")
    error = error_of(tmp_path, TWO_BODY.replace("position = [0.0, 0.2]", "position = [0.0, 0.15]"))
    assert_names(error, "gap -0.05 m (overlapping)")


def test_gap_tolerance_can_be_stated(tmp_path):
    text = TWO_BODY.replace("position = [0.0, 0.2]", "position = [0.0, 0.2001]")
    assert_names(error_of(tmp_path, text), "must touch")
    ok = text.replace("friction = 0.3", "friction = 0.3\ngap_tolerance = 1e-3")
    assert load_scenario(write(tmp_path, ok, "ok.toml")).gap_tolerance == 1e-3


@pytest.mark.parametrize("old, new, parts", [
    ("position = [0.0, 0.0]\n", "", ["body.a.position", "missing required key"]),
    ('name = "b"', 'name = "a"', ["body[1].name", "share a name"]),
    ("velocity = [0.0, -1.0]", "velocity = [0.0, 1.0]", ["body.b.velocity", "do not approach"]),
    # the value is the named body's, the other's beside it (its default too)
    ("velocity = [0.0, -1.0]", "velocity = [0.0, 1.0]",
     ["body.b.velocity = [0.0, 1.0]:", "(with body.a.velocity = [0.0, 0.0])"]),
])
def test_two_body_errors(tmp_path, old, new, parts):
    assert_names(error_of(tmp_path, TWO_BODY.replace(old, new, 1)), "bad.toml", *parts)


def test_body_count(tmp_path):
    one_body = TWO_BODY[: TWO_BODY.index('[[body]]\nname = "b"')]
    assert_names(error_of(tmp_path, one_body), "bad.toml", "body", "exactly two")
    second_body = GROUND[GROUND.index("[[body]]"):].replace('"disk"\nshape', '"d2"\nshape')
    two_on_ground = GROUND + second_body
    assert_names(error_of(tmp_path, two_on_ground), "exactly one [[body]]")


# --------------------------------------------------------------------------------------------
# Sweeps
# --------------------------------------------------------------------------------------------
@pytest.mark.parametrize("sweep, parts", [
    ('parameter = "body.disk.angel_deg"\nvalues = [1.0, 2.0]',
     ["sweep.parameter", "body.disk.angel_deg", "did you mean 'body.disk.angle_deg'",
      "friction, restitution"]),
    ('parameter = "friction"\nvalues = { start = 0.0, stop = 1.0, num = 1 }',
     ["sweep.values.num", "integer >= 2"]),
    ('parameter = "friction"\nvalues = []', ["sweep.values", "non-empty list"]),
    ('parameter = "friction"\nvalues = [0.1, "x"]', ["sweep.values[1]", "'x'", "number"]),
    ('parameter = "friction"\nvalues = [0.1, 0.1]', ["sweep.values", "repeats a value"]),
    ('parameter = "restitution"\nvalues = [0.5, 1.5]',
     ["sweep.values", "1.5", "restitution out of range at sweep point restitution=1.5", "0 … 1"]),
    ('parameter = "body.disk.velocity.y"\nvalues = [-1.0, 0.5]',
     ["body.disk.velocity", "do not approach at sweep point body.disk.velocity.y=0.5"]),
    ('parameter = "body.disk.mass"\nvalues = [1.0, -1.0]',
     ["body.disk.mass", "must be positive at sweep point body.disk.mass=-1"]),
    ('parameter = "friction"\nvalues = [0.1, 0.2]\nsteps = 3', ["sweep.steps", "unknown key"]),
])
def test_bad_sweeps(tmp_path, sweep, parts):
    assert_names(error_of(tmp_path, GROUND + "\n[sweep]\n" + sweep + "\n"), "bad.toml", *parts)


def test_sweep_over_a_two_body_angle_checks_each_point(tmp_path):
    """Turning a rod about its centre breaks contact with a disk resting off-centre on it."""
    text = TWO_BODY.replace('name = "a"\nshape = "disk"\nradius = 0.1',
                            'name = "a"\nshape = "rod"\nlength = 1.0\nradius = 0.1')
    text = text.replace("position = [0.0, 0.2]", "position = [0.3, 0.2]")
    assert load_scenario(write(tmp_path, text, "ok.toml"))
    text += '\n[sweep]\nparameter = "body.a.angle_deg"\nvalues = [0.0, 10.0]\n'
    assert_names(error_of(tmp_path, text), "must touch at sweep point body.a.angle_deg=10")


# --------------------------------------------------------------------------------------------
# Expectations, gates, engine settings, analytic systems
# --------------------------------------------------------------------------------------------
@pytest.mark.parametrize("expect, parts", [
    ("[expect.collision_type]\nnewton = 4", ["expect.collision_type.newton", "4", "1, 2, 3"]),
    ("[expect.collision_type]\npoison = 2", ["expect.collision_type.poison", "unknown key",
                                             "did you mean 'poisson'"]),
    ("[expect]\ncase = 6", ["expect.case", "6", "1 … 5"]),
    ("[expect]\ncase = [1, 1]", ["expect.case", "2 entries for 1 sweep points"]),
    ("[expect]\nenergy_gain = { newton = 1 }", ["expect.energy_gain.newton", "true or false"]),
    ("[expect]\ncolision_type = {}", ["expect.colision_type", "did you mean 'collision_type'"]),
    ('[expect.gate]\n"pymunk.acurate" = { law = "newton-lcp", max_departure = 1e-6 }',
     ["expect.gate.pymunk.acurate", "did you mean 'pymunk.accurate'"]),
    ('[expect.gate]\n"bullet3" = { law = "newton-lcp", max_departure = 1e-6 }',
     ["expect.gate.bullet3", "unknown engine"]),
    ('[expect.gate]\npymunk = { law = "newton-lcp", max_departure = -1.0 }',
     ["expect.gate.pymunk.max_departure", "-1.0", "> 0"]),
    ('[expect.gate]\npymunk = { law = "hooke", max_departure = 1.0 }',
     ["expect.gate.pymunk.law", "'hooke'", "newton, poisson"]),
    ("[engine_settings]\nbullet3 = { iterations = 3 }", ["engine_settings.bullet3", "unknown key"]),
    # a bad value names its key, not the whole table
    ("[engine_settings]\npymunk = { iterations = -5, time_step = 0.001 }",
     ["engine_settings.pymunk.iterations = -5:", "out of range", "1 <= value <= 10000"]),
])
def test_bad_expectations(tmp_path, expect, parts):
    assert_names(error_of(tmp_path, GROUND + "\n" + expect + "\n"), "bad.toml", *parts)


def test_gates_parse_quoted_and_dotted_keys(tmp_path):
    text = GROUND + ('\n[expect.gate]\n"pymunk.accurate" = { law = "newton-lcp", '
                     'max_departure = 1e-6 }\npybullet.defaults = { law = "poisson", '
                     'max_departure = 0.5 }\nmujoco = { law = "poisson", max_departure = 0.9 }\n')
    gates = load_scenario(write(tmp_path, text, "ok.toml")).expect.gates
    assert [g.source for g in gates] == ["pymunk.accurate", "pybullet.defaults", "mujoco"]


def test_a_gate_names_mujocos_second_preset_by_its_shown_name(tmp_path):
    """``mujoco.matched-bounce`` (quoted or dotted) gates the ``accurate`` role; the role's
    old name is refused with the new one."""
    for key in ('"mujoco.matched-bounce"', "mujoco.matched-bounce"):
        text = GROUND + f'\n[expect.gate]\n{key} = {{ law = "newton", max_departure = 0.5 }}\n'
        (gate,) = load_scenario(write(tmp_path, text, "ok.toml")).expect.gates
        assert (gate.engine, gate.preset, gate.source) == ("mujoco", "accurate",
                                                           "mujoco.matched-bounce")
    text = GROUND + '\n[expect.gate]\n"mujoco.accurate" = { law = "newton", max_departure = 1 }\n'
    assert_names(error_of(tmp_path, text), "bad.toml", "expect.gate.mujoco.accurate",
                 "mujoco calls this preset 'mujoco.matched-bounce'")
    text = GROUND + ('\n[expect.gate]\n"pymunk.matched-bounce" = '
                     '{ law = "newton", max_departure = 1 }\n')
    assert_names(error_of(tmp_path, text), "bad.toml", "expect.gate.pymunk.matched-bounce",
                 "unknown engine or preset")


def test_engine_settings_are_checked_by_the_adapter_when_installed(tmp_path):
    pytest.importorskip("pymunk")
    try:
        from harness.engines import load_engine

        load_engine("pymunk")
    except Exception as error:  # the adapter belongs to another module
        pytest.skip(f"pymunk adapter not available: {error}")
    good = GROUND + "\n[engine_settings.pymunk]\niterations = 50\n"
    assert load_scenario(write(tmp_path, good, "ok.toml")).engine_settings["pymunk"] == {
        "iterations": 50}
    error = error_of(tmp_path, GROUND + "\n[engine_settings.pymunk]\niteratons = 50\n")
    assert_names(error, "bad.toml", "engine_settings.pymunk.iteratons", "did you mean 'iterations'")


@pytest.mark.parametrize("old, new, parts", [
    ("delta = 0.85", "delta = 2.0", ["parameters.delta", "2.0", "|angle| < π/2"]),
    ("delta = 0.85", "delta = 0.85\nm = 0", ["parameters.m", "> 0"]),
    ("delta = 0.85", "delta = 0.85\nu = [1.0, 0.1]", ["parameters.u", "list of 4 numbers"]),
    ("delta = 0.85", "delta = 0.85\nu = [0.0, 0.0, 0.0, 0.0]", ["parameters.u", "no approach"]),
    ("delta = 0.85", "delta = 0.85\nepsilon = 1", ["parameters.epsilon", "unknown key",
                                                   "gamma, delta, m, l"]),
    ("gamma = 0.2\n", "", ["parameters.gamma", "missing required key"]),
    ('name = "sled"', 'name = "sled"\nengines = ["pymunk"]',
     ["engines", "unknown key", 'system = "two-sled"']),
    ("[parameters]", '[expect.gate]\npymunk = { law = "poisson", max_departure = 1 }\n\n'
     "[parameters]", ["expect.gate", "analytic-only"]),
    ('system = "two-sled"', 'system = "two-sleds"', ["system", "did you mean 'two-sled'",
                                                    "bodies, two-sled, matrix"]),
])
def test_two_sled_errors(tmp_path, old, new, parts):
    assert old in SLED
    assert_names(error_of(tmp_path, SLED.replace(old, new, 1)), "bad.toml", *parts)


MATRIX = """\
name = "m"
system = "matrix"
restitution = 0.5
friction = 0.3
mass_matrix = [[1.0, 0.0], [0.0, 2.0]]
wn = [0.0, 1.0]
wt = [1.0, 0.0]
u = [0.5, -1.0]
"""


@pytest.mark.parametrize("old, new, parts", [
    ("[[1.0, 0.0], [0.0, 2.0]]", "[[1.0, 0.5], [0.0, 2.0]]", ["mass_matrix", "not symmetric"]),
    ("[[1.0, 0.0], [0.0, 2.0]]", "[[1.0, 0.0], [0.0, -2.0]]",
     ["mass_matrix", "not positive definite"]),
    ("[[1.0, 0.0], [0.0, 2.0]]", "[[1.0, 0.0]]", ["mass_matrix", "square"]),
    ("wn = [0.0, 1.0]", "wn = [0.0, 1.0, 0.0]", ["wn", "list of 2 numbers"]),
    ("wt = [1.0, 0.0]", "wt = [0.0, 2.0]", ["wt", "parallel to wn"]),
    ("u = [0.5, -1.0]", "u = [0.5, 1.0]", ["u", "no approach", "wn·u < 0"]),
])
def test_matrix_errors(tmp_path, old, new, parts):
    assert load_scenario(write(tmp_path, MATRIX, "ok.toml")).matrix.u == (0.5, -1.0)
    assert_names(error_of(tmp_path, MATRIX.replace(old, new, 1)), "bad.toml", *parts)


def test_duplicate_names_across_files(tmp_path):
    write(tmp_path, GROUND, "one.toml")
    write(tmp_path, GROUND, "two.toml")
    with pytest.raises(ScenarioError) as info:
        load_scenarios(tmp_path)
    assert_names(info.value, "two.toml", "name = 'probe'", "already used by", "one.toml")


def test_load_scenarios_reports_every_bad_file(tmp_path):
    write(tmp_path, GROUND.replace("mass = 1.0", "mass = -1.0"), "a.toml")
    write(tmp_path, GROUND.replace("friction = 0.3", "friction = -1.0"), "b.toml")
    with pytest.raises(ScenarioError) as info:
        load_scenarios(tmp_path)
    assert_names(info.value, "a.toml", "b.toml", "body.disk.mass", "friction")


def test_an_unknown_tag_names_the_option(tmp_path):
    write(tmp_path, GROUND, "g.toml")
    with pytest.raises(ScenarioError) as info:
        load_scenarios([tmp_path / "g.toml"], tags="nosuchtag")
    assert str(info.value).startswith("--tags 'nosuchtag': no scenario has this tag")


# --------------------------------------------------------------------------------------------
# Ellipses
# --------------------------------------------------------------------------------------------
ELLIPSE = 'shape = "ellipse"\nsemi_x = 0.035\nsemi_y = 0.025'


def test_an_ellipse_on_the_ground_is_read_and_its_stand_in_placed(tmp_path):
    import math

    from harness.scene import ellipse

    text = GROUND.replace('shape = "disk"\nradius = 0.1', ELLIPSE).replace(
        "mass = 1.0", "mass = 0.0364\nangle_deg = 30.0")
    scene = load_scenario(write(tmp_path, text)).scene()
    body = scene.bodies[0]
    assert (body.shape.semi_x, body.shape.semi_y) == (0.035, 0.025)
    assert body.shape.vertex_at == ellipse.lowest_parameter(math.radians(30.0), 0.035, 0.025)
    assert body.position[1] == pytest.approx(-ellipse.lowest_offset(body.angle, 0.035,
                                                                     0.025)[1], abs=1e-15)


@pytest.mark.parametrize("old, new, parts", [
    ("semi_x = 0.035", "semi_x = -0.035", ["body.disk.semi_x", "-0.035"]),
    ("semi_y = 0.025", "", ["body.disk.semi_y", "missing"]),
    ("semi_y = 0.025", "semi_y = 0.025\nradius = 0.1", ["body.disk.radius", "unknown key",
                                                        "semi_x, semi_y"]),
    ("friction = 0.3", "friction = 0.3\nexpect_sequence = true",
     ["expect_sequence", "an ellipse has no corners"]),
])
def test_bad_ellipse_fields_are_named(tmp_path, old, new, parts):
    text = GROUND.replace('shape = "disk"\nradius = 0.1', ELLIPSE).replace(old, new)
    assert_names(error_of(tmp_path, text), "bad.toml", *parts)


def test_an_ellipse_between_two_bodies_is_refused(tmp_path):
    text = TWO_BODY.replace('shape = "disk"\nradius = 0.1\nmass = 1.0\nposition = [0.0, 0.0]',
                            f"{ELLIPSE}\nmass = 1.0\nposition = [0.0, 0.0]")
    error = error_of(tmp_path, text)
    assert [e.key for e in error.errors] == ["body.a.shape"], str(error)
    assert_names(error, "an ellipse touches only the ground", "[ground]")


def test_a_table_in_a_message_reads_as_the_file_writes_it(tmp_path):
    """An unknown engine's table is shown as TOML, not as Python's dict."""
    text = GROUND + '\n[engine_settings.foo]\niterations = 50\nmode = "x"\n'
    with pytest.raises(ScenarioError) as caught:
        load_scenario(write(tmp_path, text))
    message = str(caught.value)
    assert 'engine_settings.foo = { iterations = 50, mode = "x" }' in message, message
    assert "{'" not in message
