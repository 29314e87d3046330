"""The report's "Against experiments" section without the Fazeli data (issue 25, item 7)."""

import functools
import os

from harness.report import experiments
from harness.report.figure_cache import png_tag


def test_section_without_data_shows_kharaz_and_where_to_get(tmp_path, monkeypatch):
    monkeypatch.delenv("IMPACT_HARNESS_FAZELI_DIR", raising=False)
    html = experiments.experiments_section(tmp_path)
    assert "id='experiments'" in html
    assert "github.com/mcubelab/planar-impact-dataset" in html
    assert "digitised" in html and "write_usr0.f" in html  # the points' source is cited
    assert "every installed engine and preset" in html  # the engines drawn beside them
    figure = tmp_path / "figures" / experiments.KHARAZ_FIGURE
    assert figure.is_file() and figure.with_suffix(".svg").is_file()
    tag = png_tag(figure)
    assert tag
    before = os.stat(figure).st_mtime_ns
    experiments.experiments_section(tmp_path)  # same inputs: not redrawn
    assert os.stat(figure).st_mtime_ns == before and png_tag(figure) == tag


def test_section_with_an_empty_directory_names_what_is_missing(tmp_path, monkeypatch):
    data = tmp_path / "data"
    data.mkdir()
    monkeypatch.setenv("IMPACT_HARNESS_FAZELI_DIR", str(data))
    monkeypatch.setattr(experiments, "kharaz_html", lambda out_dir: "")  # drawn above
    html = experiments.experiments_section(tmp_path / "out")
    assert "The drops are not shown" in html and str(data / "data_ellipse.mat") in html


def test_a_copy_that_is_not_the_published_files_is_said_so_and_the_rest_goes_on(
        tmp_path, monkeypatch):
    data = tmp_path / "data"
    data.mkdir()
    (data / "data_ellipse.mat").write_bytes(b"not the published file")
    monkeypatch.setattr(experiments, "kharaz_html", lambda out_dir: "<kharaz>")  # drawn above
    html = experiments.experiments_section(tmp_path / "out", data)
    assert "The drops are not shown" in html and "is not the published file" in html
    assert html.endswith("<kharaz>\n</div></details>")  # the Kharaz part follows, folded


def test_the_drops_figures_and_calibration_table_from_aggregates(tmp_path, monkeypatch):
    """With aggregates (here made up, of the shape aggregates.compute returns) the section
    draws the three figures of the drops and tabulates the calibrated settings."""
    fake = fake_aggregates()
    monkeypatch.setattr(experiments, "drops_aggregates", lambda out_dir, directory: fake)
    monkeypatch.setattr(experiments, "kharaz_html", lambda out_dir: "")  # drawn above
    monkeypatch.setattr(experiments, "render_once",  # PNGs only: an SVG costs as much again
                        functools.partial(experiments.render_once, svg=False))
    data = tmp_path / "data"
    data.mkdir()
    (tmp_path / "out").mkdir()  # the report's directory exists before its sections are made
    html = experiments.experiments_section(tmp_path / "out", data)
    for name in (experiments.DENSITY_FIGURE, experiments.CDF_FIGURE, experiments.FITS_FIGURE):
        assert (tmp_path / "out" / "figures" / name).is_file() and name in html
    assert "Calibrated engine settings" in html and "cannot be calibrated" in html
    # the pymunk row: its interval, the settings chosen over the resamples, the held-out error
    assert "[0.350, 0.470]" in html and "μ 0.1 to 0.3; e 0.6" in html and "80%" in html
    assert "0.520 (6 drops; in-sample 0.380 on 6)" in html and "1,000 bootstrap" in html
    assert "seed 0" in html and "mcubelab" not in html
    assert "The data do not tell poisson from stronge" in html and "-0.0001 to 0.0001" in html
    assert "opposes the slip in 200 of 400 drops" in html
    # every engine and law at its fitted or calibrated settings, with intervals
    found = fake["calibrated_errors"]
    pymunk, mujoco = found["engines"]
    low, high = pymunk["calibrated"]["interval"]
    assert f"{pymunk['calibrated']['median']:.3f}<br>[{low:.3f}, {high:.3f}]" in html
    assert "μ 0, e 0.6" in html and "none<br>/ clipped: 2" in html
    # each engine beside Poisson on the drops it scored, and the drops it lost
    vs = pymunk["calibrated"]["vs_reference"]
    low, high = vs["reference"]["interval"]
    assert f"{vs['reference']['median']:.3f}<br>[{low:.3f}, {high:.3f}]" in html
    assert f"5<br>(law {vs['lost']['reference_median']:.3f})" in html
    assert "<i>cannot be calibrated</i>: no setting tried" in html
    assert "every drop" in html and "multi-contact: 400<br>/ —" in html
    # laws and models in one frame, both frames
    assert "Laws and models in one frame" in html and "published (default)" in html
    assert "0.191 / 0.330" in html
    assert "200 training, 200 held out" in html
    assert "length_scale 1, 8, 64" in html and "solref (0.02, 0.5), (0.02, 1)" in html
    # its text columns wrap: the table stays readable at 1400 px
    table = html[html.index("Every engine and law at its fitted"):]
    assert '<td class="note"><i>cannot be calibrated</i>' in table


def test_report_refuses_a_bad_experiments_data_before_any_work(tmp_path, capsys):
    from harness import cli

    status = cli.main(["report", "--out", str(tmp_path / "out"), "--experiments-data",
                       str(tmp_path / "absent")])
    error = capsys.readouterr().err.strip().splitlines()
    assert status == 2 and len(error) == 1 and "--experiments-data" in error[0]
    assert not (tmp_path / "out" / "index.html").exists()


def test_the_aggregates_are_kept_and_computed_again_only_when_their_inputs_change(
        tmp_path, monkeypatch):
    from types import SimpleNamespace

    from harness.experiments import aggregates, fazeli, registry

    computed = []
    hashes = {"data_ellipse.mat": "a" * 64}
    monkeypatch.setattr(registry, "verify", lambda dataset, directory: dict(hashes))
    monkeypatch.setattr(fazeli, "load", lambda directory, check_hashes=True: SimpleNamespace(
        provenance=lambda: {"directory": "/a/copy", "sha256": {}}))
    monkeypatch.setattr(aggregates, "compute",
                        lambda data, **options: computed.append(1) or {"drops": 3})
    monkeypatch.setattr(experiments, "_installed_engines", lambda: [])
    first = experiments.drops_aggregates(tmp_path, tmp_path)
    assert first["drops"] == 3 and len(computed) == 1
    # the checked hashes are kept, the copy's path never (the page is committed)
    assert first["provenance"] == {"sha256": hashes}
    assert experiments.drops_aggregates(tmp_path, tmp_path) == first and len(computed) == 1
    hashes["data_ellipse.mat"] = "b" * 64  # another copy of the files: computed again
    experiments.drops_aggregates(tmp_path, tmp_path)
    assert len(computed) == 2
    (tmp_path / experiments.DROPS_FILE).write_text("[1, 2]")  # not ours: computed again
    experiments.drops_aggregates(tmp_path, tmp_path)
    assert len(computed) == 3


def fake_aggregates() -> dict:
    import numpy as np

    from harness.experiments import aggregates

    rng = np.random.default_rng(0)
    measured = rng.normal(0.0, 1.0, 400)
    panel = aggregates.density(measured + rng.normal(0, 0.2, 400), measured)
    errors = aggregates.quantiles(rng.uniform(0, 1, 400))
    fit = {"mu": 0.04, "e": 0.55, "objective": 0.01, "held_out": 0.01,
           "mu_interval": [0.03, 0.05], "e_interval": [0.54, 0.56], "replicates": 10,
           "confidence": 0.95, "at_window_edge": 0, "on_grid_edge": False, "errors": errors}
    laws = {objective: {law: fit for law in ("newton", "poisson", "stronge")}
            for objective in aggregates.OBJECTIVES}
    return {
        "drops": 400, "post_speeds": "published", "seed": 0, "replicates": 10,
        "paper_models": {"AP Poisson": errors}, "frames": fake_frames(rng),
        "laws": laws,
        "shown": {"law": "poisson", "objective": "impulse", "mu": 0.04, "e": 0.55,
                  "speeds": ["v_x'", "v_y'", "ω'"], "units": ["m/s", "m/s", "rad/s"],
                  "density": [panel] * 3},
        "engines": [{"engine": "pymunk", "preset": "accurate", "verdicts": {"ok": 400},
                     "cdf": errors},
                    {"engine": "mujoco", "preset": "defaults",
                     "verdicts": {"multi-contact": 400}, "cdf": aggregates.quantiles([])}],
        "calibration": {"sample": {"drops": 12, "of": 400, "seed": 0}, "grid": "quick",
                        "tolerance": 1e-3, "replicates": 1000, "confidence": 0.95,
                        "results": [
                            {"engine": "pymunk", "preset": "accurate",
                             "best": {"mu": 0.1, "e": 0.6}, "objective": 0.4,
                             "moves": {"mu": 0.1, "e": 0.2}, "cannot": [], "knobs": {},
                             "objective_interval": [0.35, 0.47],
                             "settings_interval": {"mu": [0.1, 0.3], "e": [0.6, 0.6]},
                             "agree": 0.8, "unscored": 0,
                             "held_out": {"in_sample": 0.38, "held_out": 0.52,
                                          "fitting_drops": 6, "held_out_drops": 6,
                                          "picked": {"mu": 0.1, "e": 0.6}}},
                            {"engine": "mujoco", "preset": "defaults", "best": None,
                             "objective": None, "moves": {}, "cannot": [], "knobs": {},
                             "objective_interval": None, "settings_interval": None,
                             "agree": None, "held_out": None}]},
        "poisson_vs_stronge": {
            "median-error": {"difference": 0.0, "interval": [-1e-4, 1e-4], "confidence": 0.95,
                             "replicates": 1000, "objective_of_stronge": 0.36,
                             "prediction_gap": {"median": 0.001, "q99": 0.03},
                             "median_error": 0.36, "band": 0.01,
                             "verdict": "the data do not tell poisson from stronge (the "
                                        "interval contains 0)"},
            "impulse": None},
        "routh": {"incidence_ratio": {"q25": 0.16, "q50": 0.22, "q75": 0.27, "q90": 0.33},
                  "mu_coupling": {"q25": 0.01, "q50": 0.02, "q75": 0.03, "q90": 0.04},
                  "coupling_opposes_slip": 200, "drops": 400},
        "provenance": {"sha256": {"data_ellipse.mat": "0" * 64}},
        "calibrated_errors": fake_calibrated_errors(rng),
    }


def fake_frames(rng) -> dict:
    """Both frames of made-up errors, reduced by calibrated_errors' own functions."""
    from harness.experiments import calibrated_errors, frames

    law, model = rng.uniform(0, 0.8, 400), rng.uniform(0, 1, 400)
    summary = functools.partial(calibrated_errors.median_interval, replicates=50)
    fit = {"mu": 0.0, "e": 0.6, "objective": 0.3, "held_out_objective": 0.31, **summary(law),
           "vs_best_model": calibrated_errors.paired_difference(law, model, replicates=50)}
    row = {"models": {"AP Poisson": summary(model)}, "best_model": "AP Poisson",
           "fits": {"median-error": fit, "impulse": fit},
           "outside_impulse_span": {"median": 0.191, "q90": 0.33}}
    return {"frames": {name: {**row, "means": text} for name, text in frames.FRAMES.items()},
            "default": frames.DEFAULT_FRAME, "law": "poisson", "replicates": 50,
            "confidence": 0.95, "models_outside_impulse_span_max": 3e-16}


def fake_calibrated_errors(rng) -> dict:
    """Made-up per-drop errors reduced by calibrated_errors' own functions: pymunk
    calibrated, MuJoCo flagged on every drop and so not calibrated."""
    import numpy as np

    from harness.experiments import aggregates, calibrated_errors

    held = rng.uniform(0, 1, 200)
    reference = held + rng.normal(0, 0.01, 200)
    summary = functools.partial(calibrated_errors.median_interval, replicates=50)
    paired = functools.partial(calibrated_errors.paired_difference, replicates=50)
    held[:5] = np.nan  # lost: flagged
    calibrated = {"settings": {"mu": 0.0, "e": 0.6}, "training_objective": 0.3,
                  **summary(held), "flagged": {"clipped": 2},
                  "vs_reference": paired(held, reference), "cdf": aggregates.quantiles(held)}
    nothing = summary(np.full(400, np.nan))
    return {
        "objective": "median-error", "reference": "poisson", "seed": 0, "replicates": 50,
        "confidence": 0.95, "split": {"training": 200, "held_out": 200},
        "calibration": {"drops": 12, "grid": "quick", "mus": [0.0, 0.1, 0.3],
                        "es": [0.3, 0.6, 0.9],
                        "knobs": {"box2d": {"length_scale": [1.0, 8.0, 64.0]},
                                  "mujoco": {"solref": [[0.02, 0.5], [0.02, 1.0]]}},
                        "tolerance": 1e-3},
        "law_grid": {"mus": [0.0, 0.1, 0.3], "es": [0.0, 0.5, 1.0]},
        "laws": [{"law": "poisson", "fit": {"mu": 0.0, "e": 0.589}, "at_fit": summary(reference),
                  "unsolved": 0, "training_fit": {"mu": 0.0, "e": 0.57},
                  "held_out": summary(reference),
                  "held_out_vs_reference": paired(reference, reference),
                  "held_out_cdf": aggregates.quantiles(reference)}],
        "engines": [
            {"engine": "pymunk", "preset": "accurate", "cannot": None, "cannot_knobs": [],
             "at_preset": {"mu": 0.04, "e": 0.55, **summary(held), "flagged": {},
                           "vs_reference": paired(held, reference)},
             "calibrated": calibrated},
            {"engine": "mujoco", "preset": "defaults", "calibrated": None,
             "cannot": "no setting tried gives single impacts on half of the 12 training drops",
             "cannot_knobs": ["mu", "e", "solref"],
             "at_preset": {"mu": 0.04, "e": 0.55, **nothing,
                           "flagged": {"multi-contact": 400}, "vs_reference": None}}]}
