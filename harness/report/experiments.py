"""The report's "Against experiments" section (issue 25, item 7).

Always: the Kharaz curves (tangential restitution, rebound angle and spin of a disk against
incidence) for every law, with the measured points as digitised by others
(``kharaz.MEASURED``, cited). The Fazeli drops are unlicensed: this section never shows a per-drop
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
from harness.report.views import FIGURES

KHARAZ_FIGURE = "experiments-kharaz.png"
#: Incidences of the drawn curves, degrees from the normal.
INCIDENCES = np.linspace(1.0, 89.0, 177)


def kharaz_payload() -> dict:
    """What the Kharaz figure shows (its redraw key, with the report's code digest)."""
    return {"laws": list(pi.LAWS), "mu": kharaz.MU, "e": kharaz.E,
            "measured": {q: [m.incidence_deg, m.values] for q, m in kharaz.MEASURED.items()},
            "source": kharaz.SOURCE, "incidences": INCIDENCES.tolist()}


#: The three panels: the quantity, its axis label.
KHARAZ_PANELS = (("tangential_restitution", r"tangential restitution of the centre, $v_x'/v_x$"),
                 ("rebound_deg", "rebound angle (° from the normal)"),
                 ("spin", "forward spin after impact (rad/s)"))


def draw_kharaz(path: Path, tag: str | None) -> Path:
    figure = new_figure(11.0, 3.8)
    axes = figure.subplots(1, 3)
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
        measured = kharaz.MEASURED[quantity]
        axis.plot(measured.incidence_deg, measured.values, "o", mfc="none", color="black",
                  markersize=6, label="measured (digitised)")
        axis.set_xlim(0, 90)
        axis.set_xlabel("incidence (° from the normal)")
        axis.set_ylabel(label)
        axis.grid(True, color="#dddddd", linewidth=0.5)
    axes[1].plot([0, 90], [0, 90], color="#bbbbbb", linewidth=0.8, linestyle="--",
                 label="rebound = incidence")
    axes[0].legend(fontsize=8, loc="lower right")
    axes[1].legend(fontsize=8, loc="upper left", handles=axes[1].get_lines()[-1:])
    return save_png(figure, path, tag=tag)


def kharaz_html(out_dir: Path) -> str:
    figures = out_dir / FIGURES
    figures.mkdir(parents=True, exist_ok=True)
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
        "moves the measurement; dotted: the rigid stick–slip transition. Circles: the "
        "measurements as others digitised them from the published figures "
        f"({escape_html(kharaz.SOURCE)}); a second digitisation "
        f"({escape_html(kharaz.CROSS_CHECK_SOURCE)}) agrees to {spread}. The sources give "
        "no error bars. The engines' curves are printed by <code>impact-harness "
        "experiments</code> (at this scale most engine runs are flagged).")
    image = (f"<a href='{FIGURES}/{KHARAZ_FIGURE[:-4]}.svg'><img src='{FIGURES}/"
             f"{KHARAZ_FIGURE}' alt='Kharaz curves: the laws against the measured points'>"
             "</a>")
    return f"<figure>{image}<figcaption>{caption}</figcaption></figure>"


def data_directory(path: str | os.PathLike | None = None) -> Path | None:
    """The Fazeli copy's directory (``path`` or the environment variable), None without."""
    try:
        return registry.locate(registry.FAZELI_2017, path)
    except registry.DataMissing:
        return None


def experiments_section(out_dir: Path, data_path: str | os.PathLike | None = None) -> str:
    """The section's HTML; draws its figures under ``out_dir`` only when their inputs
    changed."""
    parts = ["<h2 id='experiments'>Against experiments</h2>",
             "<p>What real impacts did, beside what the laws say they would "
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
    return "\n".join(parts)
