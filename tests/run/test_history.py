"""The contact in time (issue 14, item 2): the per-step history rebuilt from the records.

The history is rebuilt, not read from the engines (harness/run/history.py): the speeds after
step k are ``u⁻ + M⁻¹(w_n P_n(k) + w_t P_t(k))`` (docs/theory.md, 'Contact terms'). Its last
step must give back the engine's own end velocities; the bar is the verdicts' impulse
residual (docs/verdicts.md: 2 % of the frame-free speed norm), the size of what a fixed
contact frame cannot explain when the configuration moves during the window.
"""

from __future__ import annotations

import math

import pytest

from harness.engines import ENGINE_NAMES
from harness.report.history import history_figure, history_records
from harness.run import runner
from harness.run.history import MAX_HISTORY_STEPS
from harness.run.verdicts import Tolerances
from harness.scenarios import SCENARIO_DIR, load_scenario, load_scenarios

# Scenes of one contact: a declared flat face (two contacts) is outside the one-contact rebuild.
SINGLE_POINT = [s for s in load_scenarios()
                if s.sweep is None and not s.analytic_only and s.contacts == "one"]
DISK = SCENARIO_DIR / "disk-oblique.toml"
SWEEP = SCENARIO_DIR / "sweep-disk-alpha.toml"


@pytest.fixture(scope="module")
def library_run():
    return runner.run(SINGLE_POINT, cache=None, workers=1, log=None)


def engine_records(outcome):
    return [r for r in outcome.records if r.source != "analytic"]


def test_every_engine_run_of_a_single_point_scenario_has_a_history(library_run):
    records = [r for r in engine_records(library_run) if not r.skipped]
    assert {r.source for r in records} == set(ENGINE_NAMES)
    for record in records:
        history = record.diagnostics.get("history")
        assert history is not None, (record.scenario, record.label)
        lengths = {len(history[key]) for key in ("step", "time_ms", "normal_impulse",
                                                 "tangential_impulse", "vn", "vt",
                                                 "penetration", "kinetic_energy")}
        assert lengths == {min(history["contact_steps"], 400) + 1}


def test_the_rebuilt_end_speeds_are_the_engines_within_the_impulse_residual(library_run):
    tolerance = Tolerances().impulse_residual
    checked = 0
    for record in engine_records(library_run):
        history = (record.diagnostics or {}).get("history")
        if history is None or record.diagnostics.get("max_contact_points") != 1:
            continue  # two points at once: outside the one-contact rebuild
        checked += 1
        assert history["end_mismatch"] <= tolerance, (record.scenario, record.label, history)
        # The last step's contact velocities are the record's, to the same bar (in m/s of
        # the approach speed, which sets the frame-free scale of a single contact).
        scale = math.hypot(record.vn_approach, record.vt_approach)
        assert abs(history["vn"][-1] - record.vn_separation) <= tolerance * scale
    assert checked >= 4 * len(ENGINE_NAMES)


def test_the_history_starts_at_the_approach_with_no_impulse(library_run):
    for record in engine_records(library_run):
        history = (record.diagnostics or {}).get("history")
        if history is None:
            continue
        assert history["normal_impulse"][0] == history["tangential_impulse"][0] == 0.0
        assert history["vn"][0] == pytest.approx(record.vn_approach, rel=1e-12, abs=1e-15)
        assert history["vt"][0] == pytest.approx(record.vt_approach, rel=1e-12, abs=1e-15)
        if history["contact_steps"] <= MAX_HISTORY_STEPS:
            assert history["step"][0] == history["step"][1] - 1  # the step before contact
        else:  # thinned evenly (Drake's 500-step contact): the first step may fall between
            spacing = math.ceil(history["contact_steps"] / MAX_HISTORY_STEPS)
            assert history["step"][0] < history["step"][1] <= history["step"][0] + spacing


def test_exact_sources_give_the_end_speeds_to_rounding(library_run):
    """pymunk's per-step impulses are its only velocity change, in doubles; MuJoCo's Euler
    step is ``q_k = q_{k-1} + h u_k``: both rebuild the end speeds to rounding (1e-9 of the
    speed norm: ~1e-16 per operation over < 100 steps and a 1e-3 s step's division)."""
    for record in engine_records(library_run):
        history = (record.diagnostics or {}).get("history")
        exact = record.source == "pymunk" or (
            record.source == "mujoco" and record.preset == "defaults")
        if history is None or not exact or record.diagnostics.get("max_contact_points") != 1:
            continue
        assert history["end_mismatch"] <= 1e-9, (record.scenario, record.label)


def test_history_is_off_for_sweeps_by_default_and_follows_the_flag():
    sweep, disk = load_scenario(SWEEP), load_scenario(DISK)
    by_default = runner.run([sweep, disk], engines=("pymunk",), presets=("defaults",),
                            workers=1, log=None)
    stored = {r.scenario: "history" in r.diagnostics for r in engine_records(by_default)}
    assert stored == {sweep.name: False, disk.name: True}
    off = runner.run([disk], engines=("pymunk",), presets=("defaults",), workers=1, log=None,
                     history=False)
    assert all("history" not in r.diagnostics for r in engine_records(off))
    on = runner.run([sweep], engines=("pymunk",), presets=("defaults",), workers=1, log=None,
                    history=True)
    assert all(r.diagnostics.get("history") for r in engine_records(on))


def test_the_figure_draws_every_single_contact_run(library_run, tmp_path):
    records = [r for r in library_run.records if r.scenario == "disk-oblique"]
    drawn = history_records(records)
    assert {r.source for r in drawn} == set(ENGINE_NAMES)
    path = history_figure("disk-oblique", records, tmp_path / "history.png")
    assert path.exists() and path.with_suffix(".svg").exists()
    laws_only = [r for r in records if r.source == "analytic"]
    assert history_figure("disk-oblique", laws_only, tmp_path / "none.png") is None
