"""Calibration of an engine's knobs (issue 25, item 4) on a law target, on synthetic drops
and, where a user's copy is given (IMPACT_HARNESS_FAZELI_DIR), on the real files."""

import os
from pathlib import Path

import numpy as np
import pytest

from harness.cli import main as cli_main
from harness.experiments import calibrate, registry

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
    assert "cannot be calibrated" in calibrate.summary(result)


def test_data_target_on_a_synthetic_copy(tmp_path, pymunk):
    from harness.experiments import drops_engines, fazeli

    write_synthetic(tmp_path, drops=30, flagged=4)  # Poisson, μ 0.3, e 0.7, plus noise
    data = fazeli.load(tmp_path, check_hashes=False)  # synthetic: not the published hashes
    impacts = fazeli.without_post_offset(data.impacts).subset(range(6))
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
    assert cli_main(["calibrate", "pymunk", "--to", "poisson", "--seed", "-1"]) == 2
    assert "--seed -1" in capsys.readouterr().err


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
