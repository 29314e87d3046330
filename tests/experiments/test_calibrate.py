"""Calibration of an engine's knobs (issue 25, item 4) on a law target, on synthetic drops
and, where a user's copy is given (IMPACT_HARNESS_FAZELI_DIR), on the real files."""

import os
from pathlib import Path

import numpy as np
import pytest

from harness.cli import main as cli_main
from harness.experiments import calibrate, frames, registry

from .conftest import write_synthetic

REAL_DIR = os.environ.get(registry.FAZELI_2017.env_var)
needs_real = pytest.mark.skipif(
    not REAL_DIR or not Path(REAL_DIR, "data_ellipse.mat").is_file(),
    reason=f"the Fazeli et al. 2017 files are not redistributable: set "
           f"{registry.FAZELI_2017.env_var} to a copy to run this test")


@pytest.fixture(scope="module")
def pymunk():
    from harness.engines import EngineNotInstalled, load_engine

    try:
        return load_engine("pymunk")
    except EngineNotInstalled as missing:
        pytest.skip(f"pymunk not installed: {missing}")


def test_law_target_finds_the_laws_friction(pymunk):
    impacts, thetas = calibrate.drop_population(6)
    result = calibrate.calibrate(pymunk, "accurate", impacts, thetas, "poisson",
                                 law_mu=0.3, law_e=0.6)
    assert result.best["mu"] == 0.3 and result.best["e"] == 0.6
    assert result.moves["mu"] > calibrate.TOLERANCE and result.moves["e"] > calibrate.TOLERANCE
    assert "best:" in calibrate.summary(result)


def test_a_knob_that_moves_nothing_cannot_calibrate(pymunk, monkeypatch):
    # The pair's μ does not matter on frictionless-looking impacts: every drop straight down
    # through the centre has no slip.
    impacts, thetas = calibrate.drop_population(4)
    impacts.speeds_before[:, 0] = 0.0
    impacts.speeds_before[:, 2] = 0.0
    thetas = np.zeros_like(thetas)
    from harness.experiments import fazeli
    from harness.scene import ellipse

    wn, wt = ellipse.jacobians(thetas, *fazeli.SEMI_AXES)
    impacts.wn[:], impacts.wt[:] = wn, wt
    result = calibrate.calibrate(pymunk, "accurate", impacts, thetas, "poisson")
    assert "mu" in result.cannot() and "e" not in result.cannot()
    text = calibrate.summary(result)
    assert "cannot be calibrated" in text
    assert "mu any (ties)" in text  # the first value wins every tie: no interval to show


def test_data_target_on_a_synthetic_copy(tmp_path, pymunk):
    from harness.experiments import drops_engines, fazeli

    write_synthetic(tmp_path, drops=30, flagged=4)  # Poisson, μ 0.3, e 0.7, plus noise
    data = fazeli.load(tmp_path, check_hashes=False)  # synthetic: not the published hashes
    impacts = frames.in_frame(data.impacts, frames.DEFAULT_FRAME).subset(range(6))
    thetas, _ = drops_engines.jacobian_angles(impacts, data.pre_impact_angles[:6])
    result = calibrate.calibrate(pymunk, "accurate", impacts, thetas, "data")
    assert result.best["mu"] == 0.3 and result.best["e"] == 0.6  # nearest cells of 0.3, 0.7
    assert "against the measured drops" in calibrate.summary(result)


def test_cli_to_a_law(capsys, pymunk):
    status = cli_main(["calibrate", "pymunk", "--to", "poisson", "--preset", "accurate",
                       "--drops", "4"])
    assert status == 0 and "best:" in capsys.readouterr().out


def test_cli_to_data_without_a_copy_is_bad_input(monkeypatch, capsys):
    monkeypatch.delenv("IMPACT_HARNESS_FAZELI_DIR", raising=False)
    assert cli_main(["calibrate", "pymunk", "--to", "data"]) == 2
    assert "planar-impact-dataset" in capsys.readouterr().err


def test_the_scored_drops_are_a_seeded_random_sample():
    rows = calibrate.sample_rows(1718, 12, seed=3)
    assert np.array_equal(rows, calibrate.sample_rows(1718, 12, seed=3))  # the seed decides
    assert not np.array_equal(rows, calibrate.sample_rows(1718, 12, seed=4))
    assert len(set(rows.tolist())) == 12 and np.all(np.diff(rows) > 0) and rows[-1] < 1718
    assert not np.array_equal(rows, np.arange(12))  # not the first drops
    assert np.array_equal(calibrate.sample_rows(5, 12), np.arange(5))  # fewer than asked: all


def test_cli_refuses_a_negative_seed(capsys):
    with pytest.raises(SystemExit) as refused:  # by the option's type, in one sentence
        cli_main(["calibrate", "pymunk", "--to", "poisson", "--seed", "-1"])
    assert refused.value.code == 2
    assert "--seed: '-1' is out of range" in capsys.readouterr().err


@needs_real
def test_real_files_a_seeded_sample_is_scored_and_recorded(capsys, pymunk):
    """On the real drops: the sample (not the file's first drops) is printed with its seed,
    and the same seed gives the same calibration."""
    arguments = ["calibrate", "pymunk", "--to", "data", "--preset", "accurate", "--drops",
                 "6", "--seed", "7", "--data", REAL_DIR]
    assert cli_main(arguments) == 0
    first = capsys.readouterr().out
    assert "impacts scored: 6 of 1718, a random sample drawn with seed 7" in first
    assert "best:" in first
    assert cli_main(arguments) == 0
    assert capsys.readouterr().out == first


# --- the intervals and the held-out error (the toy engine of tests/engines: exact Poisson) ---

@pytest.fixture(scope="module")
def toy():
    from tests.engines.toy_engine import ToyEngine

    return ToyEngine()


@pytest.fixture(scope="module")
def toy_on_synthetic_drops(tmp_path_factory, toy):
    """The toy (exact Poisson impulses) calibrated to a synthetic copy drawn from Poisson's
    law at μ 0.3, e 0.7 plus noise: on the quick grid the nearest cell, (0.3, 0.6), is the
    best one."""
    from harness.experiments import drops_engines, fazeli

    directory = tmp_path_factory.mktemp("calibrate_toy")
    write_synthetic(directory, drops=40, flagged=2, noise=0.05)
    data = fazeli.load(directory, check_hashes=False)  # synthetic: not the published hashes
    target = frames.in_frame(data.impacts, frames.DEFAULT_FRAME)
    rows = calibrate.sample_rows(len(target), 16, seed=2)
    impacts = target.subset(rows)
    thetas, _ = drops_engines.jacobian_angles(impacts, data.pre_impact_angles[rows])
    return calibrate.calibrate(toy, "accurate", impacts, thetas, "data", replicates=300,
                               seed=2)


def test_the_toy_recovers_the_known_cell_inside_its_intervals(toy_on_synthetic_drops):
    result = toy_on_synthetic_drops
    assert result.best == {"mu": 0.3, "e": 0.6}
    found = result.uncertainty
    assert found.replicates == 300 and found.unscored == 0
    for knob, value in result.best.items():
        low, high = found.settings[knob]
        assert low <= value <= high and {low, high} <= set(result.knobs[knob])
    assert found.objective.low <= result.best_objective <= found.objective.high
    assert found.objective.low < found.objective.high  # the noise gives the objective a spread
    assert found.agree > 0.5


def test_the_held_out_error_is_the_fitting_halfs_pick_on_the_other_half(
        toy_on_synthetic_drops):
    from harness.experiments import fitting

    result = toy_on_synthetic_drops
    found = result.uncertainty
    fitting_rows, held_rows = fitting.fold_splits(16, 2, seed=2)[0]
    assert len(held_rows) == found.split.held_out_drops[0] == 8
    pick = result.cells.index(next(cell for cell in result.cells
                                   if cell[0] == found.split_best[0]))
    assert found.held_out == pytest.approx(np.median(result.errors[pick, held_rows]))
    assert found.in_sample == pytest.approx(np.median(result.errors[pick, fitting_rows]))
    # no cell beats the pick on the fitting half
    assert found.in_sample == pytest.approx(min(
        np.median(result.errors[k, fitting_rows]) for k in range(len(result.cells))))
    text = calibrate.summary(result)
    assert "bootstrap: 300 resamples of the 16 drops with seed 2" in text
    assert f"{found.held_out:.4f} on the held-out half (8 drops)" in text


def test_the_same_seed_gives_the_same_intervals(toy):
    impacts, thetas = calibrate.drop_population(6, seed=1)
    first, second = (calibrate.calibrate(toy, "accurate", impacts, thetas, "poisson",
                                         replicates=50, seed=5) for _ in range(2))
    assert first.uncertainty == second.uncertainty
    assert first.uncertainty.settings == {"mu": [0.3, 0.3], "e": [0.6, 0.6]}


def test_flagged_runs_are_nan_and_a_cell_mostly_flagged_is_never_picked(toy, monkeypatch):
    """The law's own cell is flagged on 4 of 6 drops (fewer than half scored): its per-drop
    errors are NaN there, it has no objective, and neither the full sample nor the halves
    pick it."""
    impacts, thetas = calibrate.drop_population(6, seed=1)
    real_judged = calibrate.judged
    flagged_drops = {"drop-0", "drop-1", "drop-2", "drop-3"}

    def judged(run, scene):
        if (scene.friction, scene.restitution) == (0.3, 0.6) and scene.name in flagged_drops:
            return "multi-contact"
        return real_judged(run, scene)

    monkeypatch.setattr(calibrate, "judged", judged)
    result = calibrate.calibrate(toy, "accurate", impacts, thetas, "poisson", replicates=50)
    row = [settings for settings, _, _ in result.cells].index({"mu": 0.3, "e": 0.6})
    assert np.isnan(result.errors[row, :4]).all() and np.isfinite(result.errors[row, 4:]).all()
    assert result.cells[row][1] is None and result.cells[row][2] == pytest.approx(2 / 6)
    assert result.best != {"mu": 0.3, "e": 0.6}
    assert all(best != {"mu": 0.3, "e": 0.6} for best in result.uncertainty.split_best)


def test_resampling_a_near_tie_spreads_the_chosen_settings():
    """Made-up per-drop errors of three cells: the first two nearly tie, the third is far
    worse: the resamples pick both of the first two (the interval spans them), never the
    third."""
    rng = np.random.default_rng(0)
    errors = np.stack([rng.normal(0.30, 0.05, 40), rng.normal(0.30, 0.05, 40),
                       rng.normal(0.90, 0.05, 40)])
    cells = [{"k": 1.0}, {"k": 2.0}, {"k": 3.0}]
    (best,) = np.nonzero(calibrate.cell_objectives(errors)
                         == np.nanmin(calibrate.cell_objectives(errors)))[0]
    found = calibrate.uncertainty(errors, cells, int(best), {"k": [1.0, 2.0, 3.0]},
                                  replicates=400, seed=0)
    assert found.settings == {"k": [1.0, 2.0]}
    assert 0.05 < found.agree < 0.95
    assert found.objective.low < 0.30 < found.objective.high


def test_the_cli_prints_the_intervals_and_refuses_few_replicates(capsys, pymunk):
    status = cli_main(["calibrate", "pymunk", "--to", "poisson", "--preset", "accurate",
                       "--drops", "4", "--replicates", "20", "--seed", "3"])
    out = capsys.readouterr().out
    assert status == 0 and "bootstrap: 20 resamples of the 4 drops with seed 3" in out
    assert "held out: the drops split by drop into halves with seed 3" in out
    assert exit_status(cli_main, ["calibrate", "pymunk", "--to", "poisson",
                                  "--replicates", "5"]) == 2
    assert "--replicates: '5' is out of range" in capsys.readouterr().err
    # settings as words, never a dict; a data path where no data are read is refused
    assert "best: mu " in out and '{"mu"' not in out
    assert cli_main(["calibrate", "pymunk", "--to", "poisson", "--data", "/nonexistent"]) == 2
    assert "--data /nonexistent: read only with --to data" in capsys.readouterr().err
    assert "mu 0.3 is at an end of the values tried" in out and "--grid fine tries more" in out


def test_the_cli_takes_the_preset_names_users_see(capsys, monkeypatch):
    """MuJoCo's second preset is matched-bounce wherever it is printed, so calibrate takes
    that name for its role (an unknown name is refused, naming the allowed ones)."""
    from harness.engines import EngineNotInstalled, load_engine

    try:
        load_engine("mujoco")
    except EngineNotInstalled as missing:
        pytest.skip(f"mujoco: {missing}")
    asked = []
    monkeypatch.setattr(calibrate, "calibrate", lambda engine, preset, *a, **k: asked.append(
        preset))
    monkeypatch.setattr(calibrate, "summary", lambda result: "")
    assert cli_main(["calibrate", "mujoco", "--to", "poisson", "--preset", "matched-bounce",
                     "--drops", "2"]) == 0
    assert asked == ["accurate"]  # the role the name selects
    assert cli_main(["calibrate", "mujoco", "--to", "poisson", "--preset", "bogus"]) == 2
    assert "allowed: defaults, matched-bounce" in capsys.readouterr().err


def test_a_best_value_at_an_open_end_of_the_values_tried_is_said():
    """μ's largest value tried, or either end of an engine's knob, may hide a better value
    beyond it; μ = 0 and e's 0 and 1 are the physics' bounds."""
    assert calibrate.at_open_edge("mu", 0.3, [0.0, 0.1, 0.3])
    assert not calibrate.at_open_edge("mu", 0.0, [0.0, 0.1, 0.3])
    assert not calibrate.at_open_edge("mu", 0.1, [0.0, 0.1, 0.3])
    assert calibrate.at_open_edge("e", 0.9, [0.3, 0.6, 0.9])  # e could be 1
    assert not calibrate.at_open_edge("e", 1.0, [0.0, 0.5, 1.0])
    assert calibrate.at_open_edge("damping", 0.5, [1.0, 0.5, 2.0])
    assert not calibrate.at_open_edge("damping", 0.5, [0.5, 2.0])  # two values: no inside
    assert calibrate.settings_text({"mu": 0.3, "e": 0.6, "scale": 2}) == "mu 0.3, e 0.6, scale 2"
    # a list-valued knob, by the entry that varies (MuJoCo's solref damping ratio)
    solrefs = [[0.02, 0.5], [0.02, 1.0], [0.02, 2.0]]
    assert calibrate.at_open_edge("solref", [0.02, 2.0], solrefs)
    assert calibrate.at_open_edge("solref", [0.02, 0.5], solrefs)
    assert not calibrate.at_open_edge("solref", [0.02, 1.0], solrefs)
    two_varying = [[0.02, 0.5], [0.03, 1.0], [0.04, 2.0]]
    assert not calibrate.at_open_edge("solref", [0.03, 2.0], two_varying)


def test_cli_calibrates_a_registered_engine_without_knobs_and_says_why(capsys, toy_engine):
    """The toy declares no calibration knobs: calibrate takes it (any registered engine),
    fits the pair alone and says that its own settings cannot calibrate it, and why (the
    contract's default reason)."""
    from harness.engines import Engine

    status = cli_main(["calibrate", toy_engine, "--to", "poisson", "--preset", "accurate",
                       "--drops", "4", "--replicates", "10"])
    out = capsys.readouterr().out
    assert status == 0 and "best:" in out
    assert (f"its own settings: cannot be calibrated (no knobs; the pair's mu and e alone are "
            f"tried): {Engine.no_calibration_knobs_why}") in out
    assert "  mu (tried " in out and "  e (tried " in out and "approach_steps" not in out


def test_an_engines_calibration_knobs_are_tried_beside_the_pair(toy):
    """A class that declares knobs has them in the grid, each value run (the toy's
    ``approach_steps``: whole steps of free flight before the touch, which move nothing of
    its exact impulse: it cannot be calibrated by them)."""
    knobbed = type("KnobbedToy", (type(toy),),
                   {"calibration_knobs": (("approach_steps", (0.0, 2.0)),)})()
    impacts, thetas = calibrate.drop_population(4, seed=1)
    result = calibrate.calibrate(knobbed, "accurate", impacts, thetas, "poisson",
                                 replicates=10)
    assert result.knobs["approach_steps"] == [0.0, 2.0] and result.no_knobs_why is None
    assert len(result.cells) == 3 * 3 * 2
    assert "approach_steps" in result.cannot()
    text = calibrate.summary(result)
    assert "approach_steps (tried 0, 2): cannot be calibrated" in text  # not a list repr
    assert "no knobs" not in text


def test_a_presets_own_value_of_a_knob_is_always_tried(toy):
    """Calibration never does worse than the preset on the pair's grid: the preset's own
    value of a knob is tried first where the class does not list it (MuJoCo's
    matched-bounce maps e to its damping; a grid of fixed dampings alone flagged every
    cell)."""
    knobbed = type("KnobbedToy", (type(toy),),
                   {"calibration_knobs": (("approach_steps", (1.0, 2.0)),)})()
    own = knobbed.presets["accurate"]["approach_steps"]
    assert own not in (1.0, 2.0)
    assert calibrate.engine_knobs(knobbed) == {"approach_steps": [1.0, 2.0]}
    assert calibrate.engine_knobs(knobbed, "accurate") == {"approach_steps": [own, 1.0, 2.0]}
    impacts, thetas = calibrate.drop_population(4, seed=1)
    result = calibrate.calibrate(knobbed, "accurate", impacts, thetas, "poisson",
                                 replicates=10)
    assert len(result.cells) == 3 * 3 * 3
    assert {settings["approach_steps"] for settings, _, _ in result.cells} == {own, 1.0, 2.0}


def test_the_shipped_knobs_live_on_the_engine_classes():
    from harness.engines import Engine, engine_class, engine_names

    for name in engine_names():
        try:
            cls = engine_class(name)
        except ImportError:
            continue
        assert cls.calibration_knobs or cls.no_calibration_knobs_why != \
            Engine.no_calibration_knobs_why, f"{name}: no knobs and no reason of its own"
        assert {knob for knob, _ in cls.calibration_knobs} <= set(cls.setting_docs)


@pytest.mark.parametrize("option, value", [("--drops", "100000000"), ("--drops", "1"),
                                           ("--replicates", "1000000000000"),
                                           ("--law-mu", "nan"), ("--law-e", "1.5"),
                                           ("--law-mu", "-0.1")])
def test_cli_bounds_every_count_and_setting_before_any_work(option, value, capsys,
                                                             monkeypatch):
    """``--drops 100000000`` grew to 23.8 GB before it was killed; ``--law-mu nan`` ran."""
    from harness.experiments import calibrate_cli

    def no_work(name):
        raise AssertionError("work started before the options were checked")

    monkeypatch.setattr(calibrate_cli, "load_engine", no_work)
    assert exit_status(cli_main, ["calibrate", "pymunk", "--to", "poisson", option, value]) == 2
    # argparse's usage line, then one line naming the option, the value and what is allowed
    line = capsys.readouterr().err.strip().splitlines()[-1]
    assert f"{option}: '{value}' is out of range; allowed: " in line


def test_cli_a_rerun_reads_the_cache(capsys, pymunk, monkeypatch):
    """calibrate's second run with the same options runs no engine; progress on stderr."""
    command = ["calibrate", "pymunk", "--to", "poisson", "--drops", "3", "--replicates", "10",
               "--preset", "defaults"]
    assert cli_main(command) == 0
    first = capsys.readouterr()
    assert "impact-harness calibrate: pymunk (defaults)" in first.err

    def no_work(*args, **kwargs):
        raise AssertionError("computed again")

    monkeypatch.setattr(calibrate, "calibrate", no_work)
    assert cli_main(command) == 0
    second = capsys.readouterr()
    assert second.out == first.out and "read from the cache" in second.err
    assert cli_main([*command, "--law-e", "0.3"]) != 0  # the cli reports the failure
    assert "computed again" in capsys.readouterr().err


def test_the_cache_key_names_a_run_time_engine_by_its_source(toy_engine):
    """An engine registered at run time is not in the cache's code version: its class's
    source file names it in the key, so an edited adapter is computed again."""
    import hashlib
    import inspect

    from harness.experiments import cached

    found = cached.payload("calibrate", {"engine": toy_engine}, None)["engines_registered"]
    from harness.engines import engine_class

    source = Path(inspect.getfile(engine_class(toy_engine))).read_bytes()
    assert found == {toy_engine: hashlib.sha256(source).hexdigest()}


def exit_status(main, argv):
    """The status a command line ends with: what ``main`` returns, or the status argparse
    exits with when an option's type (harness.bounds.option) refuses its value."""
    try:
        return main(argv)
    except SystemExit as stop:
        return stop.code
