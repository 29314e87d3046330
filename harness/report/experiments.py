"""The report's "Against experiments" section (issue 25, item 7).

Always: the Kharaz curves (tangential restitution, rebound angle and spin of a disk against
incidence) for every law, with the recalled published points marked as unverified
(``kharaz.VERIFIED``). The Fazeli drops are unlicensed: this section never shows a per-drop
number; without a copy it says where to get one.
"""

from __future__ import annotations

import os
from html import escape as escape_html
from pathlib import Path

import numpy as np

import planar_impact as pi
from harness.experiments import kharaz, registry
from harness.plotting import new_figure, save_png
from harness.report.figures import render_once
from harness.report.markup import folded
from harness.report.views import FIGURES

KHARAZ_FIGURE = "experiments-kharaz.png"
#: Incidences of the drawn curves, degrees from the normal.
INCIDENCES = np.linspace(5.0, 85.0, 161)


def kharaz_payload() -> dict:
    """What the Kharaz figure shows (its redraw key, with the report's code digest)."""
    return {"laws": list(pi.LAWS), "mu": kharaz.MU, "e": kharaz.E,
            "points": [list(vars(p).values()) for p in kharaz.POINTS],
            "uncertainty": list(kharaz.UNCERTAINTY), "verified": kharaz.VERIFIED,
            "incidences": INCIDENCES.tolist()}


def draw_kharaz(path: Path, tag: str | None) -> Path:
    figure = new_figure(10.0, 3.4)
    axes = figure.subplots(1, 3)
    limit = kharaz.sticking_limit_deg()
    fields = (("tangential_restitution", 0, "tangential restitution of the centre"),
              ("rebound_deg", 1, "rebound angle (°)"), ("spin", 2, "forward spin (rad/s)"))
    label = "recalled points (unverified)" if not kharaz.VERIFIED else "published points"
    for name, column, title in fields:
        axis = axes[column]
        for law in pi.LAWS:
            curve = kharaz.curves(law, INCIDENCES)
            axis.plot(curve.incidence_deg, getattr(curve, name), label=law, linewidth=1.2)
        points = np.array([[p.incidence_deg, p.tangential_restitution, p.rebound_deg, p.spin]
                           for p in kharaz.POINTS])
        axis.errorbar(points[:, 0], points[:, column + 1], yerr=kharaz.UNCERTAINTY[column],
                      fmt="o", mfc="none", color="black", capsize=2, label=label)
        axis.axvspan(0, limit, color="#eeeeee", zorder=0)
        axis.set_xlabel("incidence (° from the normal)")
        axis.set_title(title, fontsize=9)
    axes[0].legend(fontsize=7)
    return save_png(figure, path, tag=tag)


def kharaz_html(out_dir: Path) -> str:
    figures = out_dir / FIGURES
    figures.mkdir(parents=True, exist_ok=True)
    render_once("experiments-kharaz", figures / KHARAZ_FIGURE, kharaz_payload(), draw_kharaz)
    limit = kharaz.sticking_limit_deg()
    caption = (
        f"A 5 mm alumina sphere at {kharaz.SPEED} m/s (Kharaz, Gorham &amp; Salman 2001) as a "
        f"disk, μ = {kharaz.MU}, e = {kharaz.E}. Every law draws the same curve (m<sub>nt</sub> "
        "= 0): read the curves as a test of the rigid picture and of μ, e, not of the law. "
        f"Grey: below {limit:.1f}°, where the rigid disk rolls at separation and the real "
        "sphere's tangential compliance, which no rigid law has, moves the measurement. "
        "The circles are values recalled from the paper's figures, <b>not verified</b> "
        "against a copy (bars: their uncertainty); no agreement is claimed.")
    image = (f"<a href='{FIGURES}/{KHARAZ_FIGURE[:-4]}.svg'><img src='{FIGURES}/"
             f"{KHARAZ_FIGURE}' alt='Kharaz curves for every law'></a>")
    return f"<figure>{image}<figcaption>{caption}</figcaption></figure>"


def data_directory(path: str | os.PathLike | None = None) -> Path | None:
    """The Fazeli copy's directory (``path`` or the environment variable), None without."""
    try:
        return registry.locate(registry.FAZELI_2017, path)
    except registry.DataMissing:
        return None


def experiments_section(out_dir: Path, data_path: str | os.PathLike | None = None) -> str:
    """The section's HTML, folded under what it shows; draws its figures under ``out_dir``
    only when their inputs changed."""
    parts = ["<p>What real impacts did, beside what the laws say they would "
             "(docs/experiments.md; <code>impact-harness experiments</code>).</p>"]
    directory = data_directory(data_path)
    if directory is None:
        parts.append(
            "<p>The planar ellipse drops of Fazeli et al. (ICRA 2017) are not shown: the "
            "files carry no licence and are read from your own copy. Get them from "
            f"{escape_html(registry.FAZELI_2017.where_to_get)}.</p>")
    else:
        parts.append(f"<p>Fazeli drops read from <code>{escape_html(str(directory))}</code>; "
                     "run <code>impact-harness experiments --data DIR</code> for the fits "
                     "(aggregates only).</p>")
    parts.append("<h3>Oblique impacts of a sphere (Kharaz et al. 2001)</h3>")
    parts.append(kharaz_html(out_dir))
    recalled = "recalled points, unverified" if not kharaz.VERIFIED else "published points"
    drops = "not shown (no copy)" if directory is None else "from your copy, aggregates only"
    return folded("experiments", "Against experiments", "\n".join(parts),
                  f"Kharaz et al. 2001 curves ({recalled}); Fazeli et al. 2017 drops {drops}")
