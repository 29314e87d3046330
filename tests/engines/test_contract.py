"""The engine contract, checked for every installed engine (missing engines skip).

Bit-exact comparisons where the computation is deterministic (reruns of one engine);
tolerances, each with its reason, only where physics differs.
"""

from __future__ import annotations

import json
import math
import sys
import tomllib
from pathlib import Path

import pytest

from harness import engines
from harness.engines import (
    ENGINE_NAMES,
    PRESET_ROLES,
    STATUSES,
    EngineNotInstalled,
    EngineRun,
    EngineSettingsError,
    Status,
    UnsupportedScene,
    available_engines,
    body_extent,
    engine_distribution,
    engine_names,
    ke_norm,
    load_engine,
)
from harness.scene import Body, Disk, Scene
from harness.scene.features import feature_at
from harness.scene.reference import reference_scenes
from tests.engines.toy_engine import ToyEngine

SCENES = reference_scenes()

# ---------------------------------------------------------------------- per-engine facts
# Per-engine expectations are the adapters' attributes (rounding, reference_statuses,
# native_2d; harness/engines/contract.py).


def rounding(engine) -> float:
    return engine.rounding


@pytest.fixture(params=ENGINE_NAMES)
def engine(load_or_skip, request):
    return load_or_skip(request.param)


# ---------------------------------------------------------------------- registry
# No engine is named here: every test runs for each engine the registry lists (a new engine
# is one module plus one registry line, docs/engines.md, 'Adding an engine').
def test_preset_roles():
    assert PRESET_ROLES == ("defaults", "accurate")


def _pinned_harness_extra() -> dict[str, str]:
    """``{distribution (lower case): version}`` pinned with ``==`` in pyproject.toml's
    ``harness`` extra."""
    text = (Path(__file__).resolve().parents[2] / "pyproject.toml").read_text("utf-8")
    extra = tomllib.loads(text)["project"]["optional-dependencies"]["harness"]
    return {name.strip().lower(): version.strip() for name, _, version in
            (requirement.partition("==") for requirement in extra) if version}


@pytest.mark.parametrize("name", ENGINE_NAMES)
def test_every_shipped_engine_is_pinned_and_documented(name):
    # Shipping an engine names its exact version in pyproject.toml (the install message and
    # provenance read the pin there) and gives it a section of docs/engines.md.
    distribution = engine_distribution(name)
    assert distribution.lower() in _pinned_harness_extra(), (
        f"pin {distribution} with == in pyproject.toml's harness extra")
    docs = (Path(__file__).resolve().parents[2] / "docs" / "engines.md").read_text("utf-8")
    headings = {line[3:].strip().lower() for line in docs.splitlines()
                if line.startswith("## ")}
    assert name.lower() in headings, f"docs/engines.md has no section '## {name}'"


def test_unknown_engine_name_lists_the_choices():
    with pytest.raises(ValueError) as caught:
        load_engine("no-such-engine")
    message = str(caught.value)
    assert "unknown engine 'no-such-engine'" in message
    assert all(repr(name) in message for name in engine_names())


def test_available_engines_reports_every_engine():
    report = available_engines()
    assert set(report) == set(engine_names())
    for reason in report.values():
        assert reason is None or "pip install" in reason


@pytest.mark.parametrize("name", ENGINE_NAMES)
def test_missing_engine_raises_import_error_naming_install(monkeypatch, name):
    # Simulate an uninstalled engine: a None entry in sys.modules makes its import fail.
    package = engines._ENGINE_MODULES[name][1]
    monkeypatch.setitem(sys.modules, package, None)
    monkeypatch.delitem(engines._LOADED, name, raising=False)
    with pytest.raises(EngineNotInstalled) as caught:
        load_engine(name)
    error = caught.value
    assert isinstance(error, ImportError)
    assert error.engine == name
    distribution = engine_distribution(name)
    version = _pinned_harness_extra()[distribution.lower()]
    assert f"pip install {distribution}=={version}" in str(error)
    assert 'pip install -e ".[harness]"' in str(error)
    report = available_engines()
    assert report[name] is not None and name in report[name]
    # The other engines are unaffected (when installed).
    for other in ENGINE_NAMES:
        if other == name:
            continue
        try:
            __import__(engines._ENGINE_MODULES[other][1])  # the engine's importable package
        except ImportError:
            continue
        assert report[other] is None


def run_or_skip(engine, scene, *args, **kwargs):
    """``engine.run(scene, ...)``, the test skipped where the engine refuses the scene with
    UnsupportedScene (as check_engine skips it)."""
    try:
        return engine.run(scene, *args, **kwargs)
    except UnsupportedScene as error:
        pytest.skip(f"{engine.name} refuses {scene.name!r}: {error}")


# ---------------------------------------------------------------------- settings
def test_presets_complete_and_json(engine):
    assert set(engine.presets) == set(PRESET_ROLES)
    keys = set(engine.setting_docs)
    for preset in PRESET_ROLES:
        settings = engine.settings(preset)
        assert set(settings) == keys
        assert json.loads(json.dumps(settings)) == settings  # plain JSON-able values
        for key in ("time_step", "max_steps", "approach_steps"):
            assert key in settings


def test_settings_returns_fresh_copies(engine):
    first = engine.settings("accurate")
    first["max_steps"] = 7
    assert engine.settings("accurate")["max_steps"] != 7


def _list_setting(engine):
    keys = [key for key, value in engine.settings("defaults").items() if isinstance(value, list)]
    if not keys:
        pytest.skip(f"{engine.name} has no list-valued setting")
    return keys[0]


def test_settings_list_values_do_not_alias_the_preset(engine):
    key = _list_setting(engine)
    before = list(engine.settings("defaults")[key])
    edited = engine.settings("defaults")
    edited[key][-1] = 0.5 if edited[key][-1] != 0.5 else 0.25
    assert engine.settings("defaults")[key] == before
    assert engine.presets["defaults"][key] == before


def test_override_lists_are_copied(engine):
    key = _list_setting(engine)
    mine = list(engine.settings("defaults")[key])
    settings = engine.settings("defaults", {key: mine})
    mine[-1] = 0.5 if mine[-1] != 0.5 else 0.25
    assert settings[key] != mine


def test_settings_list_edited_in_place_is_rechecked(engine):
    # The fast path remembers the last settings dict; an in-place edit of one of its list
    # values must be seen: the run is no longer the preset's.
    key = _list_setting(engine)
    scene = SCENES["disk"][0]
    settings = engine.settings("defaults")
    assert run_or_skip(engine, scene, settings).preset == "defaults"
    settings[key][-1] = 0.5 if settings[key][-1] != 0.5 else 0.25
    run = run_or_skip(engine, scene, settings)
    assert run.preset is None and run.settings[key] == settings[key]


def test_unknown_setting_names_engine_key_and_allowed(engine):
    with pytest.raises(EngineSettingsError) as caught:
        engine.settings("accurate", {"no_such_knob": 1})
    message = str(caught.value)
    assert engine.name in message and "no_such_knob" in message and "time_step" in message
    assert isinstance(caught.value, ValueError)


def test_unknown_preset(engine):
    with pytest.raises(ValueError, match="unknown preset 'fast'"):
        engine.settings("fast")


@pytest.mark.parametrize("key, value", [("time_step", 0.0), ("time_step", "1"), ("max_steps", 1.5),
                                        ("approach_steps", -1.0)])
def test_bad_common_setting_values(engine, key, value):
    with pytest.raises(EngineSettingsError, match=key):
        engine.settings("accurate", {key: value})


def test_settings_dict_must_be_complete(engine):
    settings = engine.settings("accurate")
    del settings["max_steps"]
    with pytest.raises(EngineSettingsError, match="max_steps"):
        engine.run(SCENES["disk"][0], settings)


def test_run_records_settings_and_preset(engine):
    scene = SCENES["disk"][0]
    run = run_or_skip(engine, scene, preset="defaults")
    assert run.preset == "defaults" and run.settings == engine.settings("defaults")
    custom = run_or_skip(engine, scene, preset="accurate", overrides={"max_steps": 12345})
    assert custom.preset is None and custom.settings["max_steps"] == 12345


# ---------------------------------------------------------------------- outputs
@pytest.mark.parametrize("preset", PRESET_ROLES)
@pytest.mark.parametrize("scene_name", sorted(SCENES))
def test_every_reference_scene_runs_ok(engine, preset, scene_name):
    scene = SCENES[scene_name][0]
    run = run_or_skip(engine, scene, preset=preset)
    assert isinstance(run, EngineRun)
    expected_status = engine.reference_statuses.get((scene_name, preset), "ok")
    assert run.status == expected_status, (run.status, run.notes)
    assert run.status in STATUSES
    assert len(run.velocities) == len(scene.bodies)
    assert all(math.isfinite(v) for v in run.u_after)
    assert run.separated and not run.step_cap_hit
    assert 1 <= run.contact_steps <= run.steps <= run.settings["max_steps"]
    assert run.first_contact_step == 1  # approach_steps 0: contact in the first step
    assert (run.max_contact_points == 1) is (expected_status == "ok")
    assert run.max_penetration >= 0.0
    assert run.normal_impulse is not None and run.normal_impulse > 0.0
    n_x, n_y = run.contact_normal
    # The engine's contact normal is the scene's. Reason for 1e-8: geometry exact to rounding;
    # pymunk's start is 1e-9 of a step short of the full rewind, which tilts a disk pair's
    # normal ~1e-10. MuJoCo's RK4 leaves the contact data of a later stage of the step, moved
    # by the relative tangential speed (~1 m/s) times dt (1e-5 s) over 0.25 m: ~4e-5, so 1e-4
    # for a soft contact (the soft_contact trait).
    # Box2D: float32 positions (its rounding).
    expected = SCENES[scene_name][2]
    tolerance = 1e-4 if engine.soft_contact else 1e-8
    if rounding(engine) > tolerance:
        tolerance = rounding(engine)
    assert math.hypot(n_x - expected[0], n_y - expected[1]) < tolerance
    if engine.native_2d:
        assert run.out_of_plane_drift is None
    else:
        assert run.out_of_plane_drift == 0.0  # planar joints: exactly in the plane
    assert run.wall_time_s > 0.0


def test_impulse_matches_momentum_change(engine):
    # Reason for 1e-9 (its rounding for Box2D): the engines' reported contact impulses against
    # m·Δv, both exact to rounding for one-step impacts; MuJoCo's is derived from momentum
    # (equal by definition).
    scene = SCENES["two-disks"][0]
    run = engine.run(scene, preset="accurate")
    body = scene.bodies[1]
    dvx = run.velocities[1][0] - body.velocity[0]
    dvy = run.velocities[1][1] - body.velocity[1]
    n_x, n_y = run.contact_normal
    t_x, t_y = n_y, -n_x
    tolerance = rounding(engine)
    assert run.normal_impulse == pytest.approx(body.mass * (dvx * n_x + dvy * n_y), abs=tolerance)
    assert run.tangential_impulse == pytest.approx(body.mass * (dvx * t_x + dvy * t_y),
                                                   abs=tolerance)


@pytest.mark.parametrize("preset", PRESET_ROLES)
def test_bit_identical_reruns_even_after_other_scenes(engine, preset):
    disk, rod, pair = SCENES["disk-spin"][0], SCENES["rod-45"][0], SCENES["two-disks"][0]
    first = engine.run(disk, preset=preset)
    engine.run(rod, preset=preset)
    engine.run(pair, preset=preset)
    engine.run(disk, preset="accurate" if preset == "defaults" else "defaults")
    second = engine.run(disk, preset=preset)
    assert first == second  # every field but wall time, floats bit for bit
    assert first.u_after.tobytes() == second.u_after.tobytes()


def test_e0_resting_contact_does_not_leak_into_next_run(engine):
    # e = 0 leaves the bodies touching at the end: the next run must not inherit contact state.
    base = SCENES["box-corner"][0]
    plastic = Scene(base.bodies, 0.0, base.friction, ground=True, name="box-plastic")
    first = engine.run(base, preset="defaults")
    engine.run(plastic, preset="defaults")
    assert engine.run(base, preset="defaults") == first


def test_no_contact_and_step_cap_statuses(engine):
    leaving = Scene((Body("disk", Disk(0.1), 1.0, (0.0, 0.2), 0.0, (0.0, 1.0), 0.0),), 0.5, 0.3,
                    ground=True, name="leaving")
    run = engine.run(leaving, preset="accurate", overrides={"max_steps": 5})
    assert run.status == "no-contact" and run.steps == 5 and run.step_cap_hit
    assert run.normal_impulse is None
    capped = engine.run(SCENES["rod-45"][0], preset="accurate", overrides={"max_steps": 1})
    assert capped.steps == 1
    if engine.soft_contact:  # a soft contact lasts ~20-50 steps (the soft_contact trait)
        assert capped.status == "no-separation" and capped.step_cap_hit


def test_runs_are_complete_engine_runs(engine):
    # Adapters build EngineRun through run_from_fields (no dataclass __init__): every field
    # is there and the run equals one built the ordinary way.
    import dataclasses

    run = engine.run(SCENES["two-disks"][0], preset="accurate")
    values = {f.name: getattr(run, f.name) for f in dataclasses.fields(EngineRun)}
    assert set(vars(run)) == set(values)
    assert EngineRun(**values) == run
    assert dataclasses.asdict(run)["steps"] == run.steps


def test_reused_scene_and_settings_objects_give_identical_runs(engine):
    # Adapters remember per (scene, settings) object; a different but equal settings dict, a
    # settings dict changed in place, and a scene rebuilt from the same values all agree.
    scene = SCENES["rod-45"][0]
    settings = engine.settings("accurate")
    first = engine.run(scene, settings)
    assert engine.run(scene, settings) == first
    assert engine.run(scene, dict(settings)) == first
    twin = Scene(scene.bodies, scene.restitution, scene.friction, ground=scene.ground,
                 name=scene.name)
    assert engine.run(twin, settings) == first
    settings["max_steps"] = 1
    capped = engine.run(scene, settings)
    assert capped.steps == 1 and capped.settings["max_steps"] == 1


def test_mutable_scene_is_not_remembered(engine):
    # A scene holding a list is unhashable, so it is checked and planned on every run: an
    # in-place change of its state takes effect.
    body = Body("disk", Disk(0.1), 1.0, [0.0, 0.1], 0.0, [0.0, -1.0], 0.0)
    scene = Scene((body,), 0.5, 0.3, ground=True, name="mutable")
    assert engine.run(scene, preset="accurate", overrides={"max_steps": 5}).status != "no-contact"
    body.velocity[1] = 1.0  # now leaving the ground
    body.position[1] = 0.2
    assert engine.run(scene, preset="accurate", overrides={"max_steps": 5}).status == "no-contact"


def test_ke_norm():
    scene = SCENES["two-disks"][0]
    u = scene.state()
    assert ke_norm(scene, u) == pytest.approx(math.sqrt(u @ scene.mass_matrix() @ u), rel=1e-15)


@pytest.mark.parametrize("field", ["position", "velocity"])
def test_vector_of_wrong_length_names_body_and_field(engine, field):
    values = {"position": (0.0, 0.1), "velocity": (0.0, -1.0)}
    values[field] = (*values[field], 5.0)
    body = Body("puck", Disk(0.1), 1.0, values["position"], 0.0, values["velocity"], 0.0)
    with pytest.raises(ValueError, match=rf"'puck' {field} must be \(x, y\).*5\.0"):
        engine.run(Scene((body,), 0.5, 0.3, ground=True, name="bad"), preset="accurate")


# ---------------------------------------------------------------------- the contract's records
def test_status_is_an_enum_that_serialises_as_its_value(engine):
    run = engine.run(SCENES["disk"][0], preset="accurate")
    assert run.status is Status.OK and run.status == "ok"
    assert json.dumps({"status": run.status}) == '{"status": "ok"}'
    assert [status.value for status in Status] == list(STATUSES)
    assert all(Status(value).meaning == meaning for value, meaning in STATUSES.items())
    capped = engine.run(SCENES["rod-45"][0], preset="accurate", overrides={"max_steps": 1})
    if capped.status is Status.NO_SEPARATION:
        assert "step cap" in capped.status_reason


@pytest.mark.parametrize("scene_name", ["disk", "rod-45", "box-corner", "two-disks"])
def test_contact_records_give_point_and_touching_feature(engine, scene_name):
    scene, contact, _ = SCENES[scene_name]
    run = engine.run(scene, preset="accurate")
    records = run.contacts
    assert len(records) == run.contact_steps and records[0].step == run.first_contact_step
    first = records[0]
    assert first.normal == run.contact_normal
    # Reason for the tolerance: an engine reports the point after the step's motion (speeds
    # up to ~1.2 m/s here) and may place it anywhere across the overlap, so one step of
    # travel plus 1 mm (pybullet's polygon margin is the largest fixed offset).
    tolerance = 2.0 * run.settings["time_step"] + 1e-3
    for point in first.points:
        assert math.hypot(point.x - contact[0], point.y - contact[1]) < tolerance
    body = scene.bodies[-1]
    # The feature the verdicts read from the record (nearest within a body's size).
    touching = feature_at(body.shape, first.poses[-1], (first.points[0].x, first.points[0].y),
                          reach=body_extent(body.shape))
    if body.shape.kind == "rod":
        assert touching == 0  # the cap at -length/2 is the lower one at 45°
    if body.shape.kind == "box":
        # The lowest corner in the scene frame is the one that strikes.
        c, s = math.cos(body.angle), math.sin(body.angle)
        heights = [s * x + c * y for x, y in body.shape.vertices().tolist()]
        assert touching == heights.index(min(heights))
    assert len(first.poses) == len(scene.bodies)


def test_impulse_source_and_energies(engine):
    scene = SCENES["two-disks"][0]
    run = engine.run(scene, preset="accurate")
    # From the engine where every step reported its impulse, else from momentum (MuJoCo's).
    reported = all(step.impulse is not None for step in run.contacts)
    assert run.impulse_source == ("engine" if reported else "momentum")
    u_before, u_after = scene.state(), run.u_after
    mass = scene.mass_matrix()
    # Reason for rel 1e-14: the same sums as u^T M u in another order (rounding only).
    assert run.energy_before == pytest.approx(0.5 * u_before @ mass @ u_before, rel=1e-14)
    assert run.energy_after == pytest.approx(0.5 * u_after @ mass @ u_after, rel=1e-14)


def test_bare_stepper_resets_steps_and_leaves_runs_unchanged(engine):
    scene = SCENES["rod-45"][0]
    settings = engine.settings("accurate")
    first = engine.run(scene, settings)
    stepper = engine.bare_stepper(scene, settings)
    try:
        for _ in range(2):
            stepper.reset()
            stepper.step(first.steps)
    finally:
        stepper.close()
    assert engine.run(scene, settings) == first


def test_the_checks_give_the_energy_weights_the_plan_uses():
    # check_scene computes each body's inertia (a polygon's is not cheap) and hands the
    # masses and inertias to the plan, which must hold what energy_weights computes.
    from harness.engines import contract
    from harness.scene import Polygon

    triangle = Polygon(((-0.1, -0.05), (0.1, -0.05), (0.0, 0.1)))
    scene = Scene((Body("a", triangle, 2.0, (0.0, 0.0), velocity=(0.1, 0.0)),
                   Body("b", Disk(0.1), 1.5, (0.0, 0.2), velocity=(0.0, -1.0))), 0.5, 0.3)
    assert contract.check_scene("toy", scene) == contract.energy_weights(scene)
    engine = ToyEngine()  # the base class's work: any adapter will do
    settings = engine.settings("accurate")
    engine._checked_scene(scene)
    plan = engine._plan_for(scene, settings, world=contract._DETACHED)
    assert plan.weights == contract.energy_weights(scene)
    assert plan.speed_scale == float(max(abs(v) for v in scene.state()))


def test_no_engine_is_named_in_this_generic_test():
    # What differs between engines is a trait of the adapter (rounding, soft_contact,
    # impulse_band, reference_statuses, native_2d), never an engine's name in a string here:
    # a fifth engine then runs every test above unchanged. Comments may give reasons.
    import ast

    tree = ast.parse(Path(__file__).read_text("utf-8"))
    named = sorted({(node.lineno, name) for node in ast.walk(tree)
                    if isinstance(node, ast.Constant) and isinstance(node.value, str)
                    for name in ENGINE_NAMES if name in node.value.lower()})
    assert not named, f"engine names in strings of this test (line, name): {named}"
