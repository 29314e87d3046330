"""The Fazeli et al. (2017) loader, on a synthetic copy in the published MAT layout and, where
a user's copy is given (IMPACT_HARNESS_FAZELI_DIR), on the real files."""

from __future__ import annotations

import os
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

import planar_impact as pi
from harness.experiments import analysis, fazeli, fitting, frames, metric, registry

REAL_DIR = os.environ.get(registry.FAZELI_2017.env_var)
needs_real = pytest.mark.skipif(
    not REAL_DIR or not Path(REAL_DIR, "data_ellipse.mat").is_file(),
    reason=f"the Fazeli et al. 2017 files are not redistributable: set "
           f"{registry.FAZELI_2017.env_var} to a copy to run this test")


def test_no_mat_file_is_ever_committed():
    root = Path(__file__).resolve().parents[2]
    if not (root / ".git").exists():
        pytest.skip("not a git checkout")
    listed = subprocess.run(["git", "ls-files", "*.mat", "**/*.mat"], cwd=root,
                            capture_output=True, text=True, check=True).stdout.split()
    assert listed == [], f"MAT files are committed (no licence allows it): {listed}"


def test_synthetic_copy_loads_with_the_flagged_drops_left_out(synthetic_copy):
    directory, truth = synthetic_copy
    data = fazeli.load(directory, check_hashes=False)
    assert len(data.impacts) == truth["drops"]
    assert data.raw_flags.shape == (truth["drops"] + truth["flagged"], 6)
    assert int(data.raw_flags.any(axis=1).sum()) == truth["flagged"]
    assert sorted(data.model_speeds) == sorted(fazeli.MODEL_NAMES)
    assert data.hashes == {}


def test_the_published_hashes_are_checked_before_reading(synthetic_copy):
    directory, _ = synthetic_copy
    with pytest.raises(registry.DataInvalid, match="SHA-256 .* is not the published"):
        fazeli.load(directory)


def test_a_copy_whose_post_speeds_lack_the_offset_is_refused(tmp_path, synthetic_copy):
    import scipy.io

    directory, _ = synthetic_copy
    for name in ("v_models.mat", "ellipse_uniform.mat"):
        shutil.copy(directory / name, tmp_path / name)
    data = scipy.io.loadmat(directory / "data_ellipse.mat")["data"][0, 0]
    fields = {name: data[name] for name in ("states_i", "states_f", "n", "d")}
    fields["states_f"] = fields["states_f"] - [0, 0, 0, 0, fazeli.POST_VY_OFFSET, 0]
    scipy.io.savemat(tmp_path / "data_ellipse.mat", {"data": fields})
    with pytest.raises(registry.DataInvalid, match="not the published offset"):
        fazeli.load(tmp_path, check_hashes=False)


def test_a_missing_copy_says_where_to_get_it(monkeypatch):
    monkeypatch.delenv(registry.FAZELI_2017.env_var, raising=False)
    with pytest.raises(registry.DataMissing, match="github.com/mcubelab/planar-impact-dataset"):
        registry.locate(registry.FAZELI_2017)
    with pytest.raises(registry.DataInvalid, match="not a directory"):
        registry.locate(registry.FAZELI_2017, "/nonexistent/fazeli")


def test_contact_space_and_speeds_agree_with_the_scalar_solver(synthetic_copy):
    """The record's vectorised (A20) terms and its speeds after, against ``pi.solve`` in
    generalized speeds, drop by drop (two independent paths)."""
    directory, _ = synthetic_copy
    impacts = fazeli.load(directory, check_hashes=False).impacts
    space = impacts.contact_space()
    result = pi.solve_batch(space.mnn, space.mnt, space.mtt, space.vn, space.vt, 0.25, 0.6,
                            law="stronge", delta=space.delta)
    after = impacts.speeds_from_impulses(result.normal_impulse, result.tangential_impulse)
    for i in range(0, len(impacts), 7):
        scalar = pi.solve(mass_matrix=impacts.mass_matrix, wn=impacts.wn[i], wt=impacts.wt[i],
                          u=impacts.speeds_before[i], mu=0.25, e=0.6, law="stronge")
        np.testing.assert_allclose(after[i], impacts.speeds_before[i] + scalar.delta_u,
                                   rtol=1e-9, atol=1e-12)


@pytest.mark.parametrize("objective", sorted(metric.OBJECTIVES))
def test_the_fit_recovers_the_known_law(synthetic_copy, objective):
    """Fitted in the frame the synthetic law's answer is written in (the published one, the
    default frame of harness/experiments/frames.py)."""
    directory, truth = synthetic_copy
    impacts = frames.in_frame(fazeli.load(directory, check_hashes=False).impacts,
                              frames.DEFAULT_FRAME)
    grid_mu = np.round(np.arange(0.0, 0.62, 0.02), 12)
    grid_e = np.round(np.arange(0.3, 1.0001, 0.02), 12)
    result = analysis.fit_laws(impacts, objective, laws=(truth["law"],), replicates=30,
                               workers=1, mus=grid_mu, es=grid_e)[truth["law"]]
    assert abs(result.fit.mu - truth["mu"]) < 0.02, result.fit
    assert abs(result.fit.e - truth["e"]) < 0.02, result.fit
    boot = result.bootstrap
    assert boot.mu.low - 0.01 <= truth["mu"] <= boot.mu.high + 0.01, boot
    assert boot.e.low - 0.01 <= truth["e"] <= boot.e.high + 0.01, boot
    assert result.held_out.held_out >= 0.9 * result.held_out.in_sample


def test_the_paper_metric_is_zero_for_exact_predictions_and_scales():
    measured = np.array([[3.0, 4.0, 1.0]])
    assert metric.normalized_error(measured, measured)[0] == 0.0
    # the spin is not part of the paper's metric; a centre error of 1 m/s on |v| = 5 is 0.2
    assert metric.normalized_error([[3.0, 5.0, 9.0]], measured)[0] == pytest.approx(0.2)


@needs_real
def test_real_files_reproduce_the_papers_median_errors():
    """The paper reports median errors of its six models between 0.43 and 0.57."""
    data = fazeli.load(Path(REAL_DIR))
    assert len(data.impacts) == 1718
    medians = {name: s["q50"] for name, s in
               analysis.paper_models(data.model_speeds, data.impacts).items()}
    assert round(min(medians.values()), 2) == 0.43, medians
    assert round(max(medians.values()), 2) == 0.57, medians
    # the Jacobians are of the pose one frame before impact: up to 1.7 mm from the lowest
    # point at the pre-impact angle (the dataset notes)
    from harness.scene import ellipse

    wn, wt = ellipse.jacobians(data.pre_impact_angles, *fazeli.SEMI_AXES)
    gap = np.hypot(wn[:, 2] - data.impacts.wn[:, 2], wt[:, 2] - data.impacts.wt[:, 2])
    assert 1.6e-3 < gap.max() < 1.8e-3 and np.median(gap) < 0.5e-3
    # the models are pure impulse predictions: their change lies in span(M⁻¹n, M⁻¹d)
    impacts = data.impacts
    inverse = np.linalg.inv(impacts.mass_matrix)
    basis = np.stack([impacts.wn @ inverse, impacts.wt @ inverse], axis=2)
    for speeds in data.model_speeds.values():
        change = speeds - impacts.speeds_before
        coefficients = np.linalg.lstsq(basis[0], change[0], rcond=None)[0]
        np.testing.assert_allclose(basis[0] @ coefficients, change[0], atol=1e-9)


def test_the_law_verdict_decides_with_a_stated_band():
    def difference(low, high):
        return analysis.LawDifference("poisson", "stronge", (low + high) / 2,
                                      fitting.Interval(low, high), 0.95, 0.0, 0.0, 0.4, 1.0)

    assert "do not tell" in difference(-0.001, 0.002).verdict()
    assert "no practical difference" in difference(-0.009, -0.001).verdict()
    assert difference(-0.05, -0.02).verdict().startswith("poisson is better")
    assert difference(0.02, 0.05).verdict().startswith("stronge is better")


@needs_real
def test_real_files_poisson_and_stronge_fit_alike_and_hold_out():
    """On these drops the two laws' fits agree and generalise: the held-out objective is
    within 3% of the in-sample one, and the verdict finds no practical difference."""
    impacts = frames.in_frame(fazeli.load(Path(REAL_DIR)).impacts, frames.DEFAULT_FRAME)
    mus = np.round(np.arange(0.0, 0.21, 0.01), 12)
    es = np.round(np.arange(0.4, 0.81, 0.01), 12)
    results = analysis.fit_laws(impacts, "impulse", laws=("poisson", "stronge"),
                                replicates=20, workers=1, mus=mus, es=es)
    for result in results.values():
        assert 0 < result.fit.mu < 0.2 and 0.4 < result.fit.e < 0.8, result.fit
        held = result.held_out
        assert abs(held.held_out - held.in_sample) <= 0.03 * held.in_sample, held
    difference = analysis.compare_laws(impacts, "impulse", results["poisson"].fit,
                                       results["stronge"].fit, replicates=200)
    verdict = difference.verdict()
    assert "do not tell" in verdict or "no practical difference" in verdict, verdict


def test_a_file_that_is_no_mat_file_is_bad_input(tmp_path, synthetic_copy):
    directory, _ = synthetic_copy
    for name in ("v_models.mat", "ellipse_uniform.mat"):
        shutil.copy(directory / name, tmp_path / name)
    (tmp_path / "data_ellipse.mat").write_bytes(b"not a MAT file at all" * 10)
    with pytest.raises(registry.DataInvalid, match="data_ellipse.mat"):
        fazeli.load(tmp_path, check_hashes=False)
