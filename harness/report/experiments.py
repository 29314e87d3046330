"""The report's "Against experiments" section (issue 25, item 7).

Always: the Kharaz curves (tangential restitution, rebound angle and spin of a disk against
incidence) for every law and every installed engine and preset, with the measured points as
digitised by others (``kharaz.MEASURED``, cited). The Fazeli drops are unlicensed: this
section shows their aggregates only (``harness.experiments.aggregates``); without a copy it
says where to get one.
"""

from __future__ import annotations

import hashlib
import json
import os
import sys
from html import escape as escape_html
from pathlib import Path

import numpy as np

import planar_impact as pi
from harness.engines import (
    EngineNotInstalled,
    engine_names,
    engine_trait,
    load_engine,
    preset_label,
)
from harness.experiments import (
    aggregates,
    calibrate,
    engine_curves,
    fazeli,
    frames,
    kharaz,
    registry,
)
from harness.experiments import cli as experiments_cli
from harness.experiments.aggregates import MIN_BIN_COUNT as MIN_BIN
from harness.experiments.calibrated_errors import interval_text, settings_text
from harness.laws import REGISTRY as LAW_REGISTRY
from harness.plotting import new_figure, save_png
from harness.report.calibrated_drops import calibrated_html
from harness.report.figure_cache import render_once, solver_digest
from harness.report.markup import folded, html_table
from harness.report.views import FIGURES, engine_style
from harness.run.provenance import package_versions
from harness.store.cache import ResultCache
from harness.store.files import make_inner_directory, write_text_atomically

KHARAZ_FIGURE = "experiments-kharaz.png"
#: Incidences of the drawn curves, degrees from the normal.
INCIDENCES = np.linspace(1.0, 89.0, 177)


#: Incidences at which every engine and preset runs the disk for the figure.
ENGINE_INCIDENCES = np.arange(5.0, 86.0, 5.0)


def kharaz_payload() -> dict:
    """What the Kharaz figure shows (its redraw key, with the report's code digest): the
    laws' inputs, the points, and what the engines' runs depend on (their code, the
    judging, the installed versions), not the runs' floats."""
    return {"laws": list(pi.LAWS), "mu": kharaz.MU, "e": kharaz.E,
            "measured": {q: [m.incidence_deg, m.values] for q, m in kharaz.MEASURED.items()},
            "source": kharaz.SOURCE, "incidences": INCIDENCES.tolist(),
            "engine_incidences": ENGINE_INCIDENCES.tolist(), "versions": package_versions(),
            "engine_code": harness_code_digest()}


def harness_code_digest() -> str:
    """The sha256 of what runs and judges the engines here: harness/experiments, the engines
    (modules and packages), the scene they build and the verdicts."""
    root = Path(__file__).resolve().parents[1]
    digest = hashlib.sha256()
    for folder in ("experiments", "engines", "scene", "run/verdicts"):
        for path in sorted((root / folder).rglob("*.py")):
            digest.update(path.relative_to(root).as_posix().encode() + b"\0"
                          + path.read_bytes())
    return digest.hexdigest()


def kharaz_engine_runs() -> list:
    """Every installed engine and preset on the disk at :data:`ENGINE_INCIDENCES`, each
    run judged (harness/experiments/engine_curves.py)."""
    return [engine_curves.engine_curves(engine, preset, ENGINE_INCIDENCES)
            for engine in _installed_engines() for preset in engine.presets]


#: The three panels: the quantity, its axis label.
KHARAZ_PANELS = (("tangential_restitution", r"tangential restitution of the centre, $v_x'/v_x$"),
                 ("rebound_deg", "rebound angle (° from the normal)"),
                 ("spin", "forward spin after impact (rad/s)"))


def draw_kharaz(path: Path, tag: str | None) -> Path:
    figure = new_figure(11.0, 4.9)
    axes = figure.subplots(1, 3)
    runs = kharaz_engine_runs()
    limit = kharaz.sticking_limit_deg()
    # Every law draws the same curve here (m_nt = 0): one line, named for all of them.
    curve = kharaz.curves(pi.LAWS[0], INCIDENCES)
    for axis, (quantity, label) in zip(axes, KHARAZ_PANELS):
        axis.axvspan(0, limit, color="#eeeeee", zorder=0,
                     label=f"rolls at separation (< {limit:.1f}°)")
        axis.axvline(limit, color="#888888", linewidth=0.8, linestyle=":",
                     label="stick–slip transition")
        axis.plot(curve.incidence_deg, getattr(curve, quantity), color="#0072B2",
                  linewidth=1.5, label=f"every law (μ {kharaz.MU}, e {kharaz.E})")
        for run in runs:  # the engines' single impacts; flagged runs are not drawn
            ok = np.array([verdict == "ok" for verdict in run.verdicts])
            if ok.any():
                colour, marker = engine_style(run.engine)
                axis.plot(run.incidence_deg[ok], getattr(run, quantity)[ok], marker,
                          color=colour, mfc="none" if run.preset == "defaults" else colour,
                          markersize=5, linestyle="none",
                          label=f"{run.engine} {preset_label(run.engine, run.preset)}")
        measured = kharaz.MEASURED[quantity]
        axis.plot(measured.incidence_deg, measured.values, "o", mfc="none", color="black",
                  markersize=7, markeredgewidth=1.3, label="measured (digitised)")
        axis.set_xlim(0, 90)
        axis.set_xlabel("incidence (° from the normal)")
        axis.set_ylabel(label)
        axis.grid(True, color="#dddddd", linewidth=0.5)
    axes[1].plot([0, 90], [0, 90], color="#bbbbbb", linewidth=0.8, linestyle="--",
                 label="rebound = incidence")
    flagged = [f"{run.engine} {preset_label(run.engine, run.preset)} "
               f"({', '.join(sorted(set(run.verdicts)))})" for run in runs
               if "ok" not in run.verdicts]
    handles, labels = axes[1].get_legend_handles_labels()
    figure.legend(handles, labels, loc="outside lower center", ncols=4, fontsize=8,
                  title=("flagged at every incidence, not drawn: " + "; ".join(flagged))
                  if flagged else None, title_fontsize=8)
    return save_png(figure, path, tag=tag)


def kharaz_html(out_dir: Path) -> str:
    figures = make_inner_directory(out_dir, FIGURES)  # never through a link
    render_once("experiments-kharaz", figures / KHARAZ_FIGURE, kharaz_payload(), draw_kharaz)
    limit = kharaz.sticking_limit_deg()
    gaps = kharaz.digitisation_gaps()
    spread = (f"{max(g[0] for g in gaps.values()):.2f}° of incidence, "
              f"{gaps['tangential_restitution'][1]:.4f} in tangential restitution, "
              f"{gaps['rebound_deg'][1]:.2f}° of rebound and {gaps['spin'][1]:.1f} rad/s "
              "of spin")
    caption = (
        f"A 5 mm alumina sphere at {kharaz.SPEED} m/s on glass (Kharaz, Gorham &amp; Salman "
        f"2001) as a disk with I = 2/5 m r², μ = {kharaz.MU}, e = {kharaz.E}. Every law draws "
        "the same curve (m<sub>nt</sub> = 0): read it as a test of the rigid picture and of "
        f"μ, e, not of the law. Grey: below {limit:.1f}°, where the rigid disk rolls at "
        "separation and the real sphere's tangential compliance, which no rigid law has, "
        "moves the measurement; dotted: the rigid stick–slip transition. Coloured markers: "
        "every installed engine and preset at every 5°, its runs judged single impacts only "
        "(hollow: <i>defaults</i>; presets that agree overlap; a flagged run is not drawn, "
        "and a preset flagged at every incidence is named above the key). Black circles: "
        "the "
        "measurements as others digitised them from the published figures "
        f"({escape_html(kharaz.SOURCE)}); a second digitisation "
        f"({escape_html(kharaz.CROSS_CHECK_SOURCE)}) agrees to {spread}. The sources give "
        "no error bars. <code>impact-harness experiments</code> prints the engines' numbers "
        "with each flagged run's reason.")
    image = (f"<a href='{FIGURES}/{KHARAZ_FIGURE[:-4]}.svg'><img src='{FIGURES}/"
             f"{KHARAZ_FIGURE}' alt='Kharaz curves: the laws against the measured points'>"
             "</a>")
    return f"<figure>{image}<figcaption>{caption}</figcaption></figure>"


#: The drops' aggregates, kept beside the figures under the digest of what made them.
DROPS_FILE = "experiments-drops.json"
DENSITY_FIGURE = "experiments-drops-density.png"
CDF_FIGURE = "experiments-drops-cdf.png"
FITS_FIGURE = "experiments-drops-fits.png"
#: Bootstrap replicates of the report's fits (the command's default is 200).
REPORT_REPLICATES = 100
#: Law colours and line styles: the law registry's (harness/laws.py), as the rest of the report.
LAW_COLOURS = {entry.name: entry.colour for entry in LAW_REGISTRY}
LAW_LINES = {entry.name: entry.line for entry in LAW_REGISTRY}


#: The kept aggregates' layout: bump when what is kept changes (2: the files' SHA-256 in the
#: provenance, never the copy's path; 3: the calibration's bootstrap intervals and held-out
#: error, Poisson against Stronge with its interval, the drops on Routh's diagram; 4: every
#: engine and law at its fitted or calibrated settings with intervals, the calibration's
#: drops from the training half; 5: both frames of the post-impact speeds, the published
#: one the default, every engine paired with the headline law on the drops it scored).
DROPS_LAYOUT = 5


def drops_key(hashes: dict[str, str]) -> str:
    """The digest of everything the drops' aggregates depend on: the files (their SHA-256),
    the code that reads, fits, runs and judges them, the registered engines (those added at
    run time too), the installed versions and the report's settings; never the results'
    floats."""
    digest = hashlib.sha256()
    digest.update(json.dumps({"layout": DROPS_LAYOUT, "hashes": hashes,
                              "versions": package_versions(), "engines": list(engine_names()),
                              "replicates": REPORT_REPLICATES, "solver": solver_digest(),
                              "code": harness_code_digest()}, sort_keys=True).encode())
    return digest.hexdigest()


def drops_aggregates(out_dir: Path, directory: Path) -> dict:
    """The aggregates of the copy in ``directory`` (checked against the published SHA-256):
    read from ``out_dir`` when made from the same inputs, else computed (minutes: every law
    fitted twice, every engine on every drop) and kept there. Raises
    :class:`registry.DataInvalid` for a copy that is not the published files."""
    hashes = registry.verify(registry.FAZELI_2017, directory)
    key = drops_key(hashes)
    path = out_dir / DROPS_FILE
    if path.is_file():
        try:
            kept = json.loads(path.read_text(encoding="utf-8"))
        except (OSError, ValueError):
            kept = {}
        if (isinstance(kept, dict) and kept.get("key") == key
                and isinstance(kept.get("aggregates"), dict)):
            return kept["aggregates"]
    data = fazeli.load(directory, check_hashes=False)  # just checked
    # The engines on the drops kept in the result cache too, where the command (and
    # findings --check through it) reads them rather than computing them again.
    result = aggregates.compute(data, engines=_installed_engines(),
                                replicates=REPORT_REPLICATES, progress=_progress,
                                cache=ResultCache(), data_sha256=hashes)
    # the files' hashes (checked above), never the copy's path: the page is committed
    result["provenance"] = {**data.provenance(), "sha256": hashes}
    result["provenance"].pop("directory", None)
    if not path.exists() or path.is_file():  # only a regular file is written over
        write_text_atomically(path, json.dumps({"key": key, "aggregates": result}, indent=1)
                              + "\n")
    return result


def _progress(text: str) -> None:
    print(f"report: Fazeli drops: {text}", file=sys.stderr, flush=True)


def _installed_engines() -> list:
    engines = []
    for name in engine_names():
        try:
            engines.append(load_engine(name))
        except EngineNotInstalled:
            continue
    return engines


def draw_density(aggregates: dict, path: Path, tag: str | None) -> Path:
    from matplotlib.colors import LogNorm

    shown = aggregates["shown"]
    figure = new_figure(11.0, 4.6)
    figure.suptitle(f"{shown['law'].capitalize()}'s law at its {shown['objective']} fit (μ "
                    f"{shown['mu']:.3f}, e {shown['e']:.3f}) against the "
                    f"{aggregates['drops']} drops: post-impact speeds", fontsize=11)
    axes = figure.subplots(1, 3)
    peak = max(max(max(row) for row in d["counts"]) for d in shown["density"])
    for axis, name, unit, panel in zip(axes, shown["speeds"], shown["units"],
                                       shown["density"]):
        edges = np.asarray(panel["edges"])
        counts = np.asarray(panel["counts"], dtype=float).T  # rows: predicted
        counts[counts == 0] = np.nan
        mesh = axis.pcolormesh(edges, edges, counts, cmap="Blues",
                               norm=LogNorm(vmin=MIN_BIN / 2, vmax=max(peak, MIN_BIN + 1)))
        axis.plot(edges[[0, -1]], edges[[0, -1]], color="#888888", linewidth=0.8,
                  linestyle="--", label="predicted = measured")
        binned = panel["binned"]
        axis.plot(binned["measured"], binned["q50"], color="#D55E00", linewidth=1.5,
                  marker="o", markersize=3, label="median predicted per bin")
        axis.fill_between(binned["measured"], binned["q25"], binned["q75"], color="#D55E00",
                          alpha=0.2, linewidth=0, label="25–75 % per bin")
        axis.set_xlim(edges[0], edges[-1])
        axis.set_ylim(edges[0], edges[-1])
        axis.set_aspect("equal")
        axis.set_xlabel(f"measured {name} ({unit})")
        axis.set_ylabel(f"predicted {name} ({unit})")
    figure.legend(handles=axes[0].get_legend_handles_labels()[0], loc="outside lower center",
                  ncols=3, fontsize=9)
    bar = figure.colorbar(mesh, ax=axes, shrink=0.8,
                          label=f"drops per bin (bins of < {MIN_BIN} not drawn)")
    ticks = [t for t in (5, 10, 20, 50, 100, 200, 500) if MIN_BIN <= t <= max(peak, 5)]
    bar.set_ticks(ticks, labels=[str(t) for t in ticks])
    bar.minorticks_off()
    return save_png(figure, path, tag=tag)


def _cdf(axis, quantile_set: dict, label: str | None, **style) -> None:
    if quantile_set["values"]:
        axis.plot(quantile_set["values"], quantile_set["levels"], label=label, **style)


#: The error-distribution figure's panels, rows × columns: every law by each objective, the
#: engines at the shown fit, and the held-out half (engines calibrated, laws fitted).
CDF_LAYOUT = (2, 2)


def draw_cdf(aggregates: dict, path: Path, tag: str | None) -> Path:
    figure = new_figure(11.0, 11.0)
    axes = figure.subplots(*CDF_LAYOUT, sharey=True).ravel()
    drops = aggregates["drops"]
    for axis, objective in zip(axes[:2], ("median-error", "impulse")):
        for law, fit in aggregates["laws"][objective].items():
            _cdf(axis, fit["errors"], f"{law} (μ {fit['mu']:.3f}, e {fit['e']:.3f})",
                 color=LAW_COLOURS.get(law), linestyle=LAW_LINES.get(law, "-"), linewidth=1.3)
        axis.set_title(f"every law fitted by {objective}", fontsize=10)
    for k, quantile_set in enumerate(aggregates["paper_models"].values()):
        # lighter than Newton's grey (the law registry's), which shares these axes
        _cdf(axes[0], quantile_set, "the paper's six models, as published" if k == 0 else None,
             color="#cccccc", linewidth=0.8)
    shown = aggregates["shown"]
    reference = aggregates["laws"][shown["objective"]][shown["law"]]
    _cdf(axes[2], reference["errors"], f"{shown['law']} (the law)", color="black",
         linewidth=2.0)
    for run in aggregates["engines"]:
        colour, marker = engine_style(run["engine"])
        dashed = run["preset"] == "defaults"
        n = run["cdf"]["drops"]
        subset = "" if n == drops else f", {n} of {drops}: a selected subset"
        label = preset_label(run["engine"], run["preset"])
        _cdf(axes[2], run["cdf"], f"{run['engine']} {label}{subset}", color=colour,
             linestyle="--" if dashed else "-", linewidth=1.2)
    flagged = [f"{r['engine']} {preset_label(r['engine'], r['preset'])}"
               for r in aggregates["engines"]
               if r["cdf"]["drops"] == 0]
    axes[2].set_title(f"engines at {shown['law']}'s {shown['objective']} fit "
                      f"(μ {shown['mu']:.3f}, e {shown['e']:.3f})", fontsize=10)
    if flagged:
        axes[2].text(0.98, 0.03, "every run flagged, not drawn:\n" + "\n".join(flagged),
                     transform=axes[2].transAxes, ha="right", va="bottom", fontsize=7)
    draw_calibrated_cdf(axes[3], aggregates.get("calibrated_errors"))
    for axis in axes:
        axis.set_xlim(0, 1.5)
        axis.set_ylim(0, 1)
        axis.grid(True, color="#dddddd", linewidth=0.5)
        axis.set_xlabel("normalized error ‖v̂ − v‖ / ‖v‖")
        axis.legend(fontsize=7.5, loc="upper center", bbox_to_anchor=(0.5, -0.16),
                    frameon=False)
    axes[0].set_ylabel(f"share of the {drops} drops with a smaller error")
    axes[2].set_ylabel("share of the drops with a smaller error")
    return save_png(figure, path, tag=tag)


def draw_calibrated_cdf(axis, found: dict | None) -> None:
    """The fourth panel: on the held-out half, every engine at its calibrated settings
    beside every law at its fit to the training half (``calibrated_errors`` aggregates)."""
    if not found:
        axis.set_axis_off()
        return
    for row in found["laws"]:
        # black, as the law in the panel beside it: the engines keep their colours
        _cdf(axis, row["held_out_cdf"], f"{row['law']} (fitted to the training half)",
             color="black", linestyle=LAW_LINES.get(row["law"], "-"), linewidth=2.0)
    held = found["split"]["held_out"]
    cannot = []
    for row in found["engines"]:
        label = f"{row['engine']} {preset_label(row['engine'], row['preset'])}"
        calibrated = row["calibrated"]
        if calibrated is None or not calibrated["cdf"]["drops"]:
            cannot.append(label)
            continue
        colour, _ = engine_style(row["engine"])
        n = calibrated["cdf"]["drops"]
        subset = "" if n == held else f", {n} of {held}"
        _cdf(axis, calibrated["cdf"], f"{label}: {settings_text(calibrated['settings'])}"
             f"{subset}", color=colour,
             linestyle="--" if row["preset"] == "defaults" else "-", linewidth=1.2)
    axis.set_title(f"held-out half ({held} drops): engines calibrated on the training half",
                   fontsize=10)
    if cannot:
        axis.text(0.98, 0.03, "cannot be calibrated or every run flagged, not drawn:\n"
                  + "\n".join(cannot), transform=axis.transAxes, ha="right", va="bottom",
                  fontsize=7)


def draw_fits(aggregates: dict, path: Path, tag: str | None) -> Path:
    figure = new_figure(9.0, 3.6)
    axes = figure.subplots(1, 2)
    rows = [(objective, law, fit) for objective in ("median-error", "impulse")
            for law, fit in aggregates["laws"][objective].items()]
    ticks = [f"{law} · {objective}" for objective, law, _ in rows]
    for axis, name, symbol in zip(axes, ("mu", "e"), ("μ", "e")):
        for k, (_, law, fit) in enumerate(rows):
            low, high = fit[f"{name}_interval"]
            value = fit[name]
            axis.errorbar([value], [k], xerr=[[value - low], [high - value]], fmt="o",
                          color=LAW_COLOURS.get(law), capsize=3, markersize=4)
            edge = " (grid edge)" if name == "mu" and fit.get("on_grid_edge") else ""
            axis.annotate(f"{value:.3f} [{low:.3f}, {high:.3f}]{edge}", (value, k),
                          xytext=(0, 5), textcoords="offset points", ha="center",
                          fontsize=7)
        axis.set_yticks(range(len(rows)), ticks if name == "mu" else [""] * len(rows),
                        fontsize=8)
        axis.set_ylim(len(rows) - 0.5, -0.8)  # first row on top, room for its label
        axis.set_title("friction μ" if name == "mu" else "restitution e", fontsize=10)
        axis.axhline(len(rows) / 2 - 0.5, color="#bbbbbb", linewidth=0.8)
        axis.grid(True, axis="x", color="#dddddd", linewidth=0.5)
        axis.set_xlabel(f"fitted {symbol} (bars: 95 % bootstrap interval, "
                        f"{aggregates['replicates']} replicates)", fontsize=9)
    return save_png(figure, path, tag=tag)


def frames_html(aggregates: dict) -> str:
    """The laws and the six models in one frame, for both frames of the post-impact speeds
    (:mod:`harness.experiments.frames`), and why the default is the default."""
    found = aggregates.get("frames")
    if not found:
        return ""
    header, rows = frames.rows(found, text=_two_lines)
    rows = [[escape_html(row[0]), *row[1:]] for row in rows]
    law = found["law"].capitalize()
    level = f"{found['confidence']:.0%}"
    return ("<h4>Laws and models in one frame</h4>"
            "<p>The published post-impact v<sub>y</sub> is the raw one plus 3gh (0.118 m/s, "
            "what gravity takes from a rising body in three frames of 1/250 s); a median "
            "error is comparable only with another in the same frame. Each column scores the "
            f"six models and {law} (fitted to that frame's speeds by each objective) against "
            f"the same speeds: medians with {level} intervals ({found['replicates']:,} "
            f"bootstrap resamples), and {law}'s median less the best model's on the same "
            "drops (paired).</p>"
            + html_table([escape_html(cell) for cell in header], rows, left=1)
            + "<p class='muted'>Why the published frame is the default: the six models' "
            "changes of speed are pure impulse predictions (outside any contact impulse by "
            f"{found['models_outside_impulse_span_max']:.0e} at most), and the paper scores "
            "them against the published speeds, where they reproduce its 0.43–0.57; adding "
            "3gh to a rising body's speed refers it to an earlier instant, towards the "
            "impact, where an impulse law predicts. The last row is the share of each "
            "measured change of speed that no contact impulse can produce: the same in both "
            "frames, so the data alone do not choose one.</p>")


def _two_lines(found: dict | None, key: str = "median") -> str:
    """A median or difference with its interval below it (a narrow table cell)."""
    return interval_text(found, key).replace(" [", "<br>[", 1)


def laws_apart_html(aggregates: dict) -> str:
    """Whether the data tell Poisson from Stronge (each objective, with its interval), and
    where the drops lie on Routh's diagram."""
    parts = ["<h4>Can the data tell Poisson from Stronge?</h4><ul>"]
    for objective, found in aggregates["poisson_vs_stronge"].items():
        if found is None:
            continue
        low, high = found["interval"]
        parts.append(
            f"<li><i>{escape_html(objective)}</i>: objective(Poisson) − objective(Stronge) = "
            f"{found['difference']:.3g}, {found['confidence']:.0%} interval {low:.3g} to "
            f"{high:.3g} (paired bootstrap, {found['replicates']:,} resamples of the drops); "
            f"their predictions of the centre's velocity differ by "
            f"{found['prediction_gap']['median']:.2%} of |v| on the median drop "
            f"({found['prediction_gap']['q99']:.2%} at the 99th percentile), against a "
            f"median error of {found['median_error']:.1%}. "
            f"{escape_html(found['verdict'].capitalize())}.</li>")
    routh = aggregates["routh"]
    ratio = ", ".join(f"{v:.3f}" for v in routh["incidence_ratio"].values())
    coupling = ", ".join(f"{v:.4f}" for v in routh["mu_coupling"].values())
    levels = ", ".join(routh["incidence_ratio"])
    parts.append("</ul><p>Where the drops lie on Routh's diagram (at the shown fit's μ): the "
                 f"incidence |v<sub>t</sub>|/|v<sub>n</sub>| has quantiles ({levels}) "
                 f"{ratio}; the coupling μ|m<sub>nt</sub>|/m<sub>nn</sub>, through which the "
                 f"laws differ, {coupling}; m<sub>nt</sub> opposes the slip in "
                 f"{routh['coupling_opposes_slip']} of {routh['drops']} drops.</p>")
    return "".join(parts)


def calibration_table(aggregates: dict) -> str:
    """The calibrated settings of every engine and preset, with the bootstrap intervals of
    the median error and of each setting chosen, and the held-out error (split by drop)."""
    calibration = aggregates["calibration"]
    level = f"{calibration['confidence']:.0%}"
    rows = []
    for result in calibration["results"]:
        interval = chosen = held = "—"
        if result["best"] is None:
            best = "cannot be calibrated: no setting tried gives single impacts on half the drops"
            objective = "—"
        else:
            best = ", ".join(f"{_symbol(k)} {v:g}" if isinstance(v, float) else
                             f"{_symbol(k)} {v}" for k, v in result["best"].items())
            objective = f"{result['objective']:.3f}"
            if result["objective_interval"] is not None:
                low, high = result["objective_interval"]
                interval = f"[{low:.3f}, {high:.3f}]"
                chosen = "; ".join(f"{_symbol(k)} any (ties)" if k in result["cannot"]
                                   else f"{_symbol(k)} {low}" if low == high
                                   else f"{_symbol(k)} {low} to {high}"
                                   for k, (low, high) in result["settings_interval"].items())
                chosen += f" (the best cell re-picked on {result['agree']:.0%})"
            split = result["held_out"]
            if split["held_out"] is not None:
                held = (f"{split['held_out']:.3f} ({split['held_out_drops']} drops; in-sample "
                        f"{split['in_sample']:.3f} on {split['fitting_drops']})")
        cannot = ", ".join(result["cannot"]) or "—"
        rows.append([escape_html(result["engine"]),
                     escape_html(preset_label(result["engine"], result["preset"])),
                     escape_html(best), objective, interval, escape_html(chosen), held,
                     escape_html(cannot)])
    sample = calibration["sample"]
    mus, es = calibrate.PAIR_GRIDS[calibration["grid"]]
    header = ["engine", "preset", "calibrated settings", "median error",
              f"its {level} interval", f"settings chosen ({level} of resamples)",
              "held-out error (in-sample)",
              "knobs that cannot calibrate it"]
    # The long text columns wrap: the table fits a 1400 px page without scrolling.
    return (html_table(header, rows, left=2,
                       column_classes=["", "", "note", "", "", "note", "note", "note"])
            + f"<p class='muted'>Grid <i>quick</i> (μ {', '.join(map(str, mus))} × e "
            f"{', '.join(map(str, es))}, "
            f"times {escape_html(_own_knobs([r['engine'] for r in calibration['results']]))})"
            ", a knob cannot calibrate an engine when none of its values moves the median "
            f"error by {calibration['tolerance']:g} or more; scored on "
            f"{sample['drops']} of the {sample['of']} drops drawn at random with seed "
            f"{sample['seed']} from the {sample.get('from', 'whole set')} (the held-out half "
            "scores the pick below; <code>impact-harness calibrate ENGINE --to data</code> "
            f"for more). Intervals: {calibration['replicates']:,} bootstrap resamples of those "
            "drops (seed as above), the best cell re-picked on each; percentile intervals, "
            "the settings' on the values tried. Held-out: the drops split by drop into "
            "halves (same seed), the best cell of one half scored on the other; its "
            "in-sample value beside it.</p>")


def _symbol(setting: str) -> str:
    """A fitted setting's name as the rest of the page writes it (μ, not mu)."""
    return "μ" if setting == "mu" else setting


def _own_knobs(engines) -> str:
    """The engines' own settings the calibration tries (their classes'
    ``calibration_knobs``), in words: ``"mujoco's solref [0.02, 0.5], ..."``."""
    knobs = [f"{engine}'s {setting} {', '.join(json.dumps(value) for value in values)}"
             for engine in dict.fromkeys(engines)
             for setting, values in engine_trait(engine, "calibration_knobs")]
    return ("; ".join(knobs) + ", and each preset's own value") if knobs else \
        "no engine's own setting"


def drops_html(out_dir: Path, aggregates: dict) -> str:
    figures = make_inner_directory(out_dir, FIGURES)  # never through a link
    payload = {"aggregates_of": aggregates.get("provenance", {}),
               "digest": aggregates_digest(aggregates)}
    parts = []
    for kind, file, draw in (("density", DENSITY_FIGURE, draw_density),
                             ("cdf", CDF_FIGURE, draw_cdf), ("fits", FITS_FIGURE, draw_fits)):
        render_once(f"experiments-drops-{kind}", figures / file, payload,
                    lambda path, tag, draw=draw: draw(aggregates, path, tag))
    shown = aggregates["shown"]
    drops = aggregates["drops"]
    hidden = sum(d["hidden_in_sparse_bins"] for d in shown["density"])
    parts.append(_figure(DENSITY_FIGURE, "predicted against measured post-impact speeds",
        f"{shown['law'].capitalize()}'s law at its <i>{shown['objective']}</i> fit (μ "
        f"{shown['mu']:.3f}, e {shown['e']:.3f}) against the {drops} processed drops "
        f"({escape_html(aggregates['post_speeds'])} post-impact speeds): how many drops "
        "fall in each bin (log scale; "
        f"{hidden} drop-bins holding fewer than {MIN_BIN} drops are left blank, so that no "
        "drop can be read off the figure), and the quartiles of the prediction in bins of "
        "the measured value. On the dashed line the prediction is exact."))
    parts.append(_figure(CDF_FIGURE, "error distributions of the laws and engines",
        "The distribution of the paper's error (the centre's velocity after impact, relative "
        "to the measured one) over the drops. Top: every law at its own fit by "
        "each objective (they give different fits); grey, the paper's six models, scored "
        "against the same speeds. Bottom left: every "
        f"engine and preset at {shown['law']}'s <i>{shown['objective']}</i> fit (dashed: "
        "the engine's <i>defaults</i>), on its runs judged single impacts only (flagged "
        "runs are not scored; a curve of fewer drops is of a selected subset and not "
        "comparable). Bottom right: the held-out half of the drops, every engine and preset "
        "at its settings calibrated on the training half beside every law at its fit to the "
        "training half (the table below gives their medians with intervals)."))
    parts.append(_figure(FITS_FIGURE, "fitted friction and restitution per law",
        "Each law's global (μ, e) by each objective with its 95 % bootstrap interval "
        f"({aggregates['replicates']} resamples of the drops, seed {aggregates['seed']}). "
        "The laws nearly coincide on this object; the objectives do not."))
    parts.append(frames_html(aggregates))
    parts.append(laws_apart_html(aggregates))
    parts.append("<h4>Calibrated engine settings</h4>" + calibration_table(aggregates))
    parts.append(calibrated_html(aggregates))
    return "\n".join(parts)


def aggregates_digest(value) -> str:
    """A digest of JSON ``value`` rounded to 6 significant digits (a figure's redraw key:
    the last bits of a float, which differ between CPUs, do not redraw it)."""
    def rounded(item):
        if isinstance(item, float):
            return float(f"{item:.6g}")
        if isinstance(item, dict):
            return {k: rounded(v) for k, v in item.items()}
        if isinstance(item, list):
            return [rounded(v) for v in item]
        return item

    return hashlib.sha256(json.dumps(rounded(value), sort_keys=True).encode()).hexdigest()


def _figure(file: str, alt: str, caption: str) -> str:
    return (f"<figure><a href='{FIGURES}/{file[:-4]}.svg'><img src='{FIGURES}/{file}' "
            f"alt='{escape_html(alt)}'></a><figcaption>{caption}</figcaption></figure>")


def data_option_problem(path: str | os.PathLike | None) -> str | None:
    """Why ``--experiments-data PATH`` cannot be used (not a directory, or not the published
    files), checked before any work; None when it can or was not given."""
    if path is None:
        return None
    try:
        registry.verify(registry.FAZELI_2017, registry.locate(registry.FAZELI_2017, path))
    except registry.DataInvalid as invalid:
        return str(invalid)
    return None


def experiments_section(out_dir: Path, data_path: str | os.PathLike | None = None) -> str:
    """The section's HTML; draws its figures under ``out_dir`` only when their inputs
    changed. With a copy of the Fazeli drops (``data_path`` or the environment variable)
    their aggregates and figures, else where to get them; a copy that is not the published
    files is said so, and the rest of the section goes on. Folded under what it shows."""
    parts = ["<p>What real impacts did, beside what the laws say they would "
             "(docs/experiments.md; <code>impact-harness experiments</code>).</p>",
             "<h3>Planar ellipse drops (Fazeli et al. 2017)</h3>"]
    where = ("Get them from " + escape_html(registry.FAZELI_2017.where_to_get) + " (for "
             "the report: <code>impact-harness report --experiments-data DIR</code>).")
    drops = "not shown (no copy)"
    try:
        directory = registry.locate(registry.FAZELI_2017, data_path)
        aggregates = drops_aggregates(out_dir, directory)
    except registry.DataMissing:
        parts.append("<p>The 1,718 processed drops of an ellipse (Fazeli et al., ICRA 2017) "
                     "are not shown: the files carry no licence and are read from your own "
                     f"copy, never committed. {where}</p>")
    except registry.DataInvalid as invalid:
        parts.append(f"<p>The drops are not shown: {escape_html(str(invalid))}. {where}</p>")
        drops = "not shown (not the published files)"
    else:
        drops = "from your copy, aggregates only"
        hashes = ", ".join(f"{escape_html(name)} {digest[:12]}…" for name, digest
                           in aggregates["provenance"].get("sha256", {}).items())
        parts.append(f"<p>{aggregates['drops']} processed drops read from your copy (SHA-256 "
                     f"{hashes}: the published files). Only aggregates are shown: the files "
                     "carry no licence.</p>")
        parts.append(drops_html(out_dir, aggregates))
    parts.append("<h3>Oblique impacts of a sphere (Kharaz et al. 2001)</h3>")
    parts.append(kharaz_html(out_dir))
    return folded("experiments", "Against experiments", "\n".join(parts),
                  "Kharaz et al. 2001 curves with digitised measured points; Fazeli et al. "
                  f"2017 drops {drops}")


def stated_numbers() -> dict[str, str]:
    """The numbers docs/experiments.md states (``stated experiments.KEY``): what
    ``impact-harness experiments`` gives with its defaults on the copy that
    ``IMPACT_HARNESS_FAZELI_DIR`` names, its tables as the command prints them. Read from
    the result cache when those were computed before (minutes otherwise). Raises
    :class:`registry.DataMissing` without a copy."""
    data = fazeli.load(registry.locate(registry.FAZELI_2017, None))
    options = experiments_cli.default_options()
    found = experiments_cli.computed_once(options, data, list(engine_names()), ResultCache(),
                                          echo=False)
    text, drops = found["text"], found["output"]["fazeli2017"]
    numbers = {name: section_tables(text, heading) for name, heading in (
        ("models", "### The paper's metric on its six models"),
        ("frames", "### Laws and models in one frame"), ("laws", "### Every law fitted"),
        ("engines", "### The engines on the drops"),
        ("calibrated", "### Every engine and law at its fitted or calibrated settings"))}
    headline = drops["headline"]
    numbers["headline.mu"], numbers["headline.e"] = f"{headline['mu']:.3f}", \
        f"{headline['e']:.3f}"
    frames_found = drops["frames"]
    for frame, row in frames_found["frames"].items():
        medians = [model["median"] for model in row["models"].values()]
        numbers[f"{frame}.models-low"] = f"{min(medians):.3f}"
        numbers[f"{frame}.models-high"] = f"{max(medians):.3f}"
        for objective, fit in row["fits"].items():
            numbers[f"{frame}.{objective}"] = f"{fit['median']:.3f}"
            numbers[f"{frame}.{objective}.vs-best"] = f"{fit['vs_best_model']['difference']:+.3f}"
            numbers[f"{frame}.{objective}.e"] = f"{fit['e']:.3f}"
        numbers[f"{frame}.span"] = f"{row['outside_impulse_span']['median']:.3f}"
    numbers["models-span"] = f"{frames_found['models_outside_impulse_span_max']:.0e}"
    for row in drops["engines_on_drops"]:  # at the headline fit, beside the law
        name, vs = f"engines.{row['engine']}.{row['preset']}", row["vs_reference"]
        numbers[f"{name}.scored"] = f"{row['verdicts'].get('ok', 0):,}"
        if vs is not None:
            numbers[f"{name}.median"] = f"{vs['median']['median']:.3f}"
            numbers[f"{name}.law"] = f"{vs['reference']['median']:.3f}"
            numbers[f"{name}.difference"] = f"{vs['difference']:+.3f}"
            if vs["lost"]["drops"]:
                numbers[f"{name}.lost-law"] = f"{vs['lost']['reference_median']:.3f}"
    for row in drops["calibrated_errors"]["engines"]:  # calibrated, on the held-out half
        name = f"calibrated.{row['engine']}.{row['preset']}"
        vs = row["calibrated"] and row["calibrated"]["vs_reference"]
        if vs:
            numbers[f"{name}.median"] = f"{vs['median']['median']:.3f}"
            numbers[f"{name}.law"] = f"{vs['reference']['median']:.3f}"
            numbers[f"{name}.difference"] = f"{vs['difference']:+.3f}"
            numbers[f"{name}.lost"] = f"{vs['lost']['drops']:,}"
            if vs["lost"]["drops"]:
                numbers[f"{name}.lost-law"] = f"{vs['lost']['reference_median']:.3f}"
    law = next(row for row in drops["calibrated_errors"]["laws"] if row["law"] == "poisson")
    numbers["calibrated.poisson.held-out"] = f"{law['held_out']['median']:.3f}"
    numbers["calibrated.poisson.e"] = f"{law['training_fit']['e']:.3f}"
    apart = drops["poisson_vs_stronge"]
    numbers["apart.difference"] = f"{apart['objective_difference']:.3g}"
    numbers["apart.low"] = f"{apart['interval']['low']:.3g}"
    numbers["apart.high"] = f"{apart['interval']['high']:.3g}"
    numbers["apart.gap-median"] = f"{apart['prediction_gap_median']:.2%}"
    numbers["apart.gap-q99"] = f"{apart['prediction_gap_q99']:.2%}"
    routh = drops["routh"]
    numbers["routh.opposes"] = f"{routh['coupling_opposes_slip']:,}"
    numbers["routh.coupling"] = f"{routh['mu_coupling']['q50']:.2f}"
    return numbers


def section_tables(text: str, heading: str) -> str:
    """The Markdown tables (their lines starting with ``|``) of the section of ``text``
    under the first line starting with ``heading``, up to the next heading; a blank line
    between two tables."""
    lines = text.splitlines()
    start = next(k for k, line in enumerate(lines) if line.startswith(heading))
    tables: list[list[str]] = []
    previous = False
    for line in lines[start + 1:]:
        if line.startswith("#"):
            break
        if line.startswith("|"):
            if not previous:
                tables.append([])
            tables[-1].append(line)
        previous = line.startswith("|")
    return "\n\n".join("\n".join(table) for table in tables)
