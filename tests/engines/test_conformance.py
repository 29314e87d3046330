"""The conformance kit (harness.engines.conformance) and a fifth engine added in one module:
the toy of tests/engines/toy_engine.py passes check_engine and shows up in the runner's
records, the report, the survey, `bench --speed-accuracy` and the cache-put bench once
registered, with no other file naming it."""

from __future__ import annotations

import dataclasses
import json
import math
import re

import numpy as np
import pytest

from harness import cli, report
from harness import engines as registry
from harness.bench import accuracy, cache_put
from harness.engines.conformance import check_engine
from harness.engines.contract import UnsupportedScene
from harness.engines.scene_setup import ke_norm
from harness.run import runner
from harness.run.records import Results
from harness.scenarios import load_scenario
from harness.scene.geometry import impact_problem, scene_contact
from harness.scene.reference import reference_scenes
from harness.store.cache import ResultCache
from harness.survey import cli as survey_cli
from harness.survey.population import resolve_populations
from tests.engines.toy_engine import ToyEngine
from tests.error_bounds import U, gamma
from tests.theory import law_bounds


@pytest.fixture
def toy(toy_beside_the_others):
    """The toy registered beside the shipped engines (tests/conftest.py)."""
    return toy_beside_the_others


def test_the_toy_conforms_and_its_traits_come_from_its_class(toy):
    assert check_engine(toy) == []
    assert check_engine(ToyEngine) == []
    assert registry.engine_trait(toy, "plot_style") == ToyEngine.plot_style
    assert registry.engine_trait(toy, "speed_caps") is None  # the contract's default
    assert toy in registry.engine_names()


@pytest.mark.kernel_sensitive  # its physics checks decide within stated bands
@pytest.mark.parametrize("name", registry.ENGINE_NAMES)
def test_every_shipped_engine_conforms(load_or_skip, name):
    assert check_engine(load_or_skip(name)) == []


def test_the_kit_names_each_broken_promise():
    class Undescribed(ToyEngine):
        description = ""
        plot_style = ("#000000",)

    class Lenient(ToyEngine):
        def _check_key(self, key):  # accepts any key
            return None

    class Unseparated(ToyEngine):
        def _step(self, world):  # the contact never ends
            contact = super()._step(world)
            return contact if contact is not None else (((0.0, 0.0, 0.0),), (0.0, 1.0),
                                                        (0.0, 0.0), 1.0)

    class Misdeclared(ToyEngine):
        native_2d = False  # yet it measures no drift
        rounding = 1

    failures = check_engine(Misdeclared)
    assert any(".rounding" in line for line in failures)
    failures = check_engine(type("Misdeclared2d", (ToyEngine,), {"native_2d": False}))
    assert any("native_2d is False" in line for line in failures)
    failures = check_engine(Undescribed)
    assert any(".description" in line for line in failures)
    assert any(".plot_style" in line for line in failures)
    assert any("accepts an unknown key" in line for line in check_engine(Lenient))
    assert any("expected a separation" in line for line in check_engine(Unseparated))


# Broken adapters an author could write from the docs (the tester's four of issue 36): each
# keeps the contract's shape and determinism, and breaks one physical promise.
class SpinFlipped(ToyEngine):
    """Reads ω with the wrong sign (a 3-D engine's joint about +y turns clockwise)."""

    def _read_velocities(self, world):
        return tuple((v_x, v_y, -omega) for v_x, v_y, omega in super()._read_velocities(world))


class NormalFlipped(ToyEngine):
    """Reports the contact normal from B into A."""

    def _step(self, world):
        contact = super()._step(world)
        if contact is None:
            return None
        points, (n_x, n_y), impulse, pressure = contact
        return points, (-n_x, -n_y), impulse, pressure


class FrictionIgnored(ToyEngine):
    """Never gives the pair its μ (the engine's 0 stays)."""

    def _prepare(self, world, scene, settings, start, weights):
        return super()._prepare(world, dataclasses.replace(scene, friction=0.0), settings,
                                start, weights)


class ImpulseZeroed(ToyEngine):
    """Reports no impulse for a step that applied one."""

    def _step(self, world):
        contact = super()._step(world)
        if contact is None:
            return None
        points, normal, _, _ = contact
        return points, normal, (0.0, 0.0), 0.0


@pytest.mark.parametrize("broken, sentence", [
    (SpinFlipped, "the spin of body B turns against the moment of the impulse"),
    (NormalFlipped, "does not point out of the ground (+y): a normal flipped?"),
    (FrictionIgnored, "friction is not used: with μ = 0.3 the oblique impact changes the slip "
                      "by 0 m/s"),
    (ImpulseZeroed, "the reported impulse does not explain the change of momentum of body B"),
])
def test_the_kit_fails_each_broken_physical_promise_with_its_sentence(broken, sentence):
    failures = check_engine(broken)
    for role in registry.PRESET_ROLES:  # under each preset, once per promise
        named = [line for line in failures if sentence in line and f"preset {role!r}" in line]
        assert len(named) == 1, (role, failures)
    # the shape, the settings and the runs' determinism are still the contract's
    assert not [line for line in failures if "physics" not in line and "preset" not in line]


def test_the_physics_checks_bite_on_a_shipped_engine(load_or_skip):
    # The same flip in pymunk's adapter: its physics is exact, so only the kit's sentence
    # tells them apart (the checks are not the toy's alone).
    engine_class = type(load_or_skip("pymunk"))

    class PymunkSpinFlipped(engine_class):
        def _read_velocities(self, world):
            return tuple((v_x, v_y, -omega)
                         for v_x, v_y, omega in super()._read_velocities(world))

    failures = check_engine(PymunkSpinFlipped)
    assert any("turns against the moment of the impulse" in line for line in failures)
    assert check_engine(engine_class) == []


def test_the_kit_holds_a_restitution_and_an_own_law_claim():
    class Plastic(ToyEngine):  # always e = 0
        def _prepare(self, world, scene, settings, start, weights):
            return super()._prepare(world, dataclasses.replace(scene, restitution=0.0),
                                    settings, start, weights)

    failures = check_engine(Plastic)
    assert sum("restitution is not used" in line for line in failures) == 2  # both presets
    assert any("does not meet its own law 'poisson'" in line for line in failures)
    # A preset that ignores e by design says why, and is not held to it.
    declared = type("PlasticDefaults", (Plastic,), {
        "restitution_unused": {"defaults": "a reason of the test"}})
    assert sum("restitution is not used" in line for line in check_engine(declared)) == 1
    # Claiming another law than the one it solves: the toy solves Poisson's, not Newton's.
    claims = type("ClaimsNewtonLcp", (ToyEngine,), {"own_law": "newton-lcp"})
    assert any("does not meet its own law 'newton-lcp'" in line
               for line in check_engine(claims))


# The reviewer's broken adapters of issue 36: each breaks one more promise. The kit as first
# merged passed six of them (μ or e scaled, the impulse as Δv on an engine of the ground alone,
# a contact point misplaced): the sliding disk, the pair's-e band and the point check catch them.
def _pair(name, **change):
    """A toy that gives the pair other values than the scene's (``change``: field -> f(scene))."""
    def _prepare(self, world, scene, settings, start, weights):
        values = {field: rule(scene) for field, rule in change.items()}
        return ToyEngine._prepare(self, world, dataclasses.replace(scene, **values), settings,
                                  start, weights)
    return type(name, (ToyEngine,), {"_prepare": _prepare})


def _reported(name, edit):
    """A toy whose ``_step`` reports ``edit(world, contact)`` for the contact it applied."""
    def _step(self, world):
        contact = ToyEngine._step(self, world)
        return None if contact is None else edit(self, world, contact)
    return type(name, (ToyEngine,), {"_step": _step})


def _ground_only(cls):
    """``cls`` refusing two bodies: the two disks are no longer among the kit's cases."""
    def _build(self, scene, settings, *, contacts=True):
        if not scene.ground:
            raise UnsupportedScene("ground only")
        return cls._build(self, scene, settings, contacts=contacts)
    return type(f"GroundOnly{cls.__name__}", (cls,), {"_build": _build})


def _tangential_flipped(self, world, contact):
    points, (n_x, n_y), (p_x, p_y), pressure = contact
    normal, tangential = p_x * n_x + p_y * n_y, p_x * n_y - p_y * n_x
    return points, (n_x, n_y), (normal * n_x - tangential * n_y,
                                normal * n_y + tangential * n_x), pressure


def _point_at_centre(self, world, contact):
    _, normal, impulse, pressure = contact
    x, y, _ = self._read_poses(world)[-1]
    return ((x, y, 0.0),), normal, impulse, pressure


def _point_on_the_far_side(self, world, contact):
    points, normal, impulse, pressure = contact
    x, y, _ = self._read_poses(world)[-1]
    return (tuple((2 * x - p_x, 2 * y - p_y, depth) for p_x, p_y, depth in points), normal,
            impulse, pressure)


def _mass_ignored(self, world, contact):  # reports Δv for the impulse m Δv
    points, normal, (p_x, p_y), pressure = contact
    return points, normal, (p_x / world.mass, p_y / world.mass), pressure / world.mass


class BodyFrameVelocities(ToyEngine):
    """Reads the velocities in the body's frame, not the world's."""

    def _read_velocities(self, world):
        poses = self._read_poses(world)
        return tuple((math.cos(theta) * v_x + math.sin(theta) * v_y,
                      -math.sin(theta) * v_x + math.cos(theta) * v_y, omega)
                     for (v_x, v_y, omega), (_, _, theta)
                     in zip(super()._read_velocities(world), poses))


class SpinInDegrees(ToyEngine):
    def _read_velocities(self, world):
        return tuple((v_x, v_y, math.degrees(omega))
                     for v_x, v_y, omega in super()._read_velocities(world))


@pytest.mark.parametrize("broken, sentence", [
    (_pair("MuDoubled", friction=lambda scene: 2.0 * scene.friction),
     "the pair's μ is not the one used: a disk sliding at 2 m/s with μ = 0.1 gets a friction "
     "impulse of 1.2 N s against the slip for a normal impulse of 6 N s, an effective μ of 0.2"),
    (_pair("MuHalved", friction=lambda scene: 0.5 * scene.friction),
     "an effective μ of 0.05"),
    (_pair("EScaled", restitution=lambda scene: 0.7 * scene.restitution),
     "the pair's e is not the one used: a direct impact at 3 m/s with e = 0.2 separates at "
     "0.42 m/s where the laws give 0.6 m/s"),
    (_pair("EPlastic", restitution=lambda scene: 0.0), "restitution is not used"),
    (_pair("EElastic", restitution=lambda scene: 1.0), "restitution is not used"),
    (_reported("TangentialFlipped", _tangential_flipped),
     "the reported impulse does not explain the change of momentum of body B"),
    (_ground_only(_reported("MassIgnored", _mass_ignored)),
     "scene 'kit-sliding': the reported impulse does not explain the change of momentum of "
     "body B: m Δv = (-0.6, 6) N s but the normal and impulses reported give (-0.3, 3) N s"),
    (_reported("PointAtCentre", _point_at_centre),
     "scene 'kit-oblique': the reported contact point"),
    (_reported("PointOnTheFarSide", _point_on_the_far_side),
     "scene 'kit-oblique': the reported contact point"),
    (BodyFrameVelocities, "the reported impulse does not explain the change of momentum"),
    (SpinInDegrees, "the reported impulse does not explain the change of spin of body B"),
])
def test_the_kit_fails_the_reviewers_broken_adapters_with_their_sentence(broken, sentence):
    failures = check_engine(broken)
    for role in registry.PRESET_ROLES:  # under each preset, once per promise
        named = [line for line in failures if sentence in line and f"preset {role!r}" in line]
        assert len(named) == 1, (role, failures)


def test_a_law_claimed_is_checked_where_the_laws_part():
    def refusing(cls, kinds):
        def _build(self, scene, settings, *, contacts=True):
            if any(body.shape.kind in kinds for body in scene.bodies):
                raise UnsupportedScene(f"no {kinds}")
            return cls._build(self, scene, settings, contacts=contacts)
        return type(f"Refusing{cls.__name__}", (cls,), {"_build": _build})

    # The toy solves Poisson's law; on the disks every law gives its answer, so a claim of
    # Newton's is caught on the box alone when the engine builds no capsule ...
    claims = type("ClaimsNewtonLcp", (ToyEngine,), {"own_law": "newton-lcp"})
    assert [line for line in check_engine(refusing(claims, ("rod",)))
            if "own law" in line] == [
        "preset 'accurate' does not meet its own law 'newton-lcp' (own_law) on the canonical "
        "case 'box-corner': departure 0.206 > 0.001 from planar_impact's answer"]
    assert check_engine(refusing(ToyEngine, ("rod",))) == []
    # ... and an engine of disks alone cannot back a claim of a law at all.
    disks_only = refusing(ToyEngine, ("rod", "box", "polygon", "ellipse"))
    assert check_engine(disks_only) == [
        "preset 'accurate': own_law 'poisson' cannot be checked: the engine refuses 'rod-45' "
        "and 'box-corner', where the laws part (on the disks every law gives one answer); "
        "claim 'converged' (with bench_reference) instead"]
    converged = type("Converged", (disks_only,), {"own_law": "converged",
                                                  "bench_reference": "accurate"})
    assert check_engine(converged) == []


def test_the_kit_names_an_unhashable_world_key_and_a_converged_law_without_reference():
    class ListKeyed(ToyEngine):
        def _world_key(self, scene, settings):
            return [len(scene.bodies)]

    assert any("returns an unhashable key" in line
               for line in check_engine(ListKeyed))
    converged = type("Converged", (ToyEngine,), {"own_law": "converged"})
    assert any(".bench_reference: own_law 'converged' needs the label" in line
               for line in check_engine(converged))
    named = type("ConvergedNamed", (ToyEngine,), {"own_law": "converged",
                                                  "bench_reference": "accurate"})
    assert check_engine(named) == []


def test_register_refuses_a_taken_name_or_a_misnamed_class(toy):
    with pytest.raises(ValueError, match="already registered"):
        registry.register_engine("pymunk", ToyEngine)
    with pytest.raises(ValueError, match="already registered"):
        registry.register_engine(toy, ToyEngine)
    with pytest.raises(ValueError, match="named 'toy'"):
        registry.register_engine("other", ToyEngine)


def test_the_toy_runs_through_the_runner_the_report_and_the_survey(toy, tmp_path):
    # A scenario file names the shipped engines (the reader's default); add the toy to it.
    scenario = load_scenario("scenarios/disk-oblique.toml")
    scenario = dataclasses.replace(scenario, engines=(*scenario.engines, toy))
    outcome = runner.run([scenario], engines=("pymunk", toy), presets=("accurate",),
                         cache=None, workers=1, log=None)
    toy_records = [r for r in outcome.records if r.source == toy]
    assert toy_records and all(r.status == "ok" for r in toy_records)
    # The toy applies Poisson's answer itself: the same solve (geometry.scene_contact and
    # impact_problem, then solve) of the same floats as the runner's Poisson reference, in one
    # process: bit for bit, so its departure is exactly 0 (not a band).
    assert all(r.departure["poisson"] == 0.0 for r in toy_records)
    results = Results(records=outcome.records, provenance=outcome.provenance,
                      scenarios=outcome.scenarios)
    written = report.write_report(results, tmp_path / "report", workers=1,
                                  scenario_figures="none", svg="none")
    page = written["html"].read_text(encoding="utf-8")
    assert ToyEngine.description in page and ToyEngine.preset_why["accurate"] in page

    survey = survey_cli.run_survey(resolve_populations(["spinning-disk"]), 3, 0, [toy],
                                   ["accurate"], workers=1, echo=lambda _: None)
    engines = np.asarray(survey["runs"]["engine"])
    assert (engines == toy).sum() == 3


def toy_departure_bound(scene, contact, normal, recorded) -> float:
    """A derived bound on the toy's departure from the bench's Poisson reference on one
    reference scene: each solve within its derived bound of its own problem's exact answer
    (law_bounds.solve_with_delta_u_bound, then the addition u + Δu's rounding), the two
    problems (the declared contact, the toy's scene_contact) apart by exactly the difference
    of their exact answers (law_bounds.exact_u_after, in Fractions); the difference's
    rounding, ``ke_norm``'s sums and roots and the quotient's, ``(1 + γ_k)``. Checks first
    that the recorded departure is that of these two solves, bit for bit."""
    mu, e = scene.friction, scene.restitution
    touching = scene_contact(scene)
    problems = (impact_problem(scene, contact, normal),
                impact_problem(scene, touching.point, touching.normal))
    solved = [law_bounds.solve_with_delta_u_bound(problem, mu, e, "poisson")
              for problem in problems]
    reference, toy = (result.u_after for result, _ in solved)
    assert accuracy.departure(scene, toy, reference) == recorded  # the same solves
    exact = [law_bounds.exact_u_after(problem, mu, e, "poisson") for problem in problems]
    apart = [float(abs(a - b)) for a, b in zip(*exact)]
    speeds = np.add(solved[0][1], solved[1][1]) + np.add(apart, U * (np.abs(reference)
                                                                     + np.abs(toy)))
    weights = [w for body in scene.bodies
               for w in (body.mass, body.mass, body.moment_of_inertia)]
    norm = math.sqrt(math.fsum(w * c * c for w, c in zip(weights, speeds * (1 + U))))
    return norm / ke_norm(scene, scene.state()) * (1 + gamma(4 * len(weights) + 8))


def test_the_toy_alone_goes_through_bench_speed_accuracy(tmp_path, capsys, toy_engine):
    # The toy_engine fixture lists the toy as the only engine: `bench --speed-accuracy`
    # measures what the registry lists, the shipped four named nowhere in the bench.
    out = tmp_path / "bench"
    assert cli.main(["bench", "--speed-accuracy", "--quick", "--out", str(out)]) == 0
    table = json.loads((out / "bench.json").read_text(encoding="utf-8"))["speed_accuracy"]
    assert list(table["engines"]) == [toy_engine]
    result = table["engines"][toy_engine]
    assert result["own_law"] == ToyEngine.own_law and result["version"] == ToyEngine.version
    assert {row["setting"] for row in result["rows"]} == {label for label, _, _ in
                                                         ToyEngine.bench_sweep(True)}
    assert len(result["rows"]) == len(ToyEngine.bench_sweep(True)) * 4  # four families
    assert all(row["status"] == "ok" and row["time_per_impact_s"] > 0
               for row in result["rows"])
    # The toy applies Poisson's impulse exactly, on every family and setting, and declares
    # Poisson its own law: the cheapest setting reaches it within each threshold.
    assert result["own_law"] == "poisson"
    assert all(row["departure"]["own"] == row["departure"]["poisson"] for row in result["rows"])
    # Kind: a cross-implementation comparison, a derived bound (toy_departure_bound): the
    # bench's reference solves its hand-built scenes' declared contact, the toy the contact
    # geometry.scene_contact computes (the same point and normal to rounding). Measured:
    # departures 0 on three families; 2.7e-16 on two-bodies against a bound of 1.4e-11,
    # 0.002 % of it (the solves' backward-error bounds are worst cases).
    for family, key in accuracy.FAMILIES.items():
        recorded = {row["departure"]["poisson"] for row in result["rows"]
                    if row["family"] == family}
        (departure,) = recorded  # every setting: the same impulse
        assert departure <= toy_departure_bound(*reference_scenes()[key], departure)
    assert all(cell["setting"] != "not reachable" for cell in result["cheapest"].values())
    assert (out / result["figure"]).is_file() and result["figure"] == f"pareto-{toy_engine}.png"
    # The batch of the worker scaling is the slowest listed engine's: the toy's.
    assert table["scaling"]["engine"] == toy_engine and table["scaling"]["identical_results"]
    assert capsys.readouterr().out.count(f"\n{toy_engine} ") == 1  # its row of the table


def test_the_toy_alone_goes_through_the_cache_put_bench(tmp_path, toy_engine):
    # A library file that names no engines (nor gates on the shipped ones, which are hidden
    # here) runs every registered engine: the toy alone.
    scenario = load_scenario("scenarios/disk-topspin.toml")
    assert scenario.engines == (toy_engine,)
    outputs = cache_put.engine_outputs(4, scenarios=[scenario])
    assert len(outputs) == 4
    # Every output is the toy's (the only engine listed), one per preset role, cycled: its
    # velocities are Poisson's for the scene, its step the preset's.
    scene = scenario.scene(scenario.point_list()[0])
    contact = scene_contact(scene)
    poisson = impact_problem(scene, contact.point, contact.normal).solve(
        mu=scene.friction, e=scene.restitution, law="poisson").u_after
    steps = [ToyEngine.presets[role]["time_step"] for role in registry.PRESET_ROLES]
    assert [output["time_step"] for output in outputs] == steps * 2
    for output in outputs:
        # Bit for bit: the toy keeps that same solve's u_after (one process, one kernel), and
        # its flight moves positions only.
        assert np.array_equal(np.ravel(output["velocities"]), poisson), (output["velocities"],
                                                                          poisson)
    wall, user, system = cache_put.time_puts(outputs, tmp_path)
    assert wall > 0 and user >= 0 and system >= 0
    cache = ResultCache(tmp_path, version="bench")
    stored = [cache.get(cache.key({"run": index})) for index in range(len(outputs))]
    assert stored == [json.loads(json.dumps(output)) for output in outputs]


def test_a_default_survey_leaves_out_the_pairs_the_engine_class_names(tmp_path, monkeypatch,
                                                                       toy_engine):
    import pyarrow.parquet as pq

    # survey_left_out is read from the engine's class (MuJoCo's matched-bounce declares it):
    # here the toy's accurate preset, left out of a default survey with the class's reason.
    monkeypatch.setattr(ToyEngine, "survey_left_out", {"accurate": "a reason of the test"})
    arguments = ["survey", "spinning-disk", "--samples", "2", "--workers", "1", "--no-figures"]
    assert cli.main([*arguments, "--out", str(tmp_path / "default")]) == 0
    settings = json.loads((tmp_path / "default" / survey_cli.SETTINGS_FILE).read_text("utf-8"))
    assert settings["engines"] == [toy_engine] and settings["presets"] == ["defaults",
                                                                           "accurate"]
    assert list(settings["left_out"]) == [f"{toy_engine}.accurate"]
    why = settings["left_out"][f"{toy_engine}.accurate"]
    assert why.startswith("a reason of the test; ")
    # The option the reason gives runs every pair: it is not a no-op.
    advised = re.search(r"`--preset ([^`]+)`", why).group(1)
    assert cli.main([*arguments, "--preset", advised, "--out", str(tmp_path / "named")]) == 0
    settings = json.loads((tmp_path / "named" / survey_cli.SETTINGS_FILE).read_text("utf-8"))
    assert settings["left_out"] == {}
    runs = pq.read_table(tmp_path / "named" / "runs.parquet").to_pydict()
    assert set(runs["preset"]) == {"defaults", "accurate"}
