"""What a stress run writes: the Markdown report, the engine CSV and the figures."""

from __future__ import annotations

import csv
import io
import math
from pathlib import Path

import numpy as np

from harness.engines import source_label
from harness.store.files import save_figure, write_text_atomically
from harness.stress.engines import OUTCOME_COLOURS, OUTCOMES
from harness.stress.solver import BOUNDARIES

#: The stress families' values as a reader names them, with units (``engine_cases``).
CASE_UNITS = {"mass": ("mass", "kg"), "size": ("size L", "m"), "speed": ("speed", "m/s"),
              "grazing": ("|v_n|/|v_t|", ""), "time_step": ("time step", "s")}
SHAPE_TITLES = {"disk": "disk (radius 0.1 L) on the ground",
                "rod": "45° rod (length L) on the ground"}


#: What every case keeps but the one quantity its family changes (``engine_cases``' base).
REFERENCE_CASE = "1 kg, L = 1 m, 1 m/s at 45°, e 0.5, μ 0.3, the preset's time step"


def number_text(value: float) -> str:
    """``1e6``, ``1e-6``, ``0.001``, ``100``: ``{:g}`` without its exponent's sign and zeros."""
    text = f"{value:g}"
    mantissa, _, exponent = text.partition("e")
    return f"{mantissa}e{int(exponent)}" if exponent else text


def case_text(record: dict) -> str:
    """A stress case's column label, with its unit: ``speed 1e4 m/s``, ``e 1, μ 10``."""
    family, value = record["family"], record["value"]
    if family == "reference":
        return "reference"
    if family == "e-mu":
        return f"e {value[0]:g}, μ {value[1]:g}"
    name, unit = CASE_UNITS.get(family, (family, ""))
    return f"{name} {number_text(value)} {unit}".rstrip()


def table_cell(text: str) -> str:
    """``text`` as one cell of a Markdown table: its ``|`` (``|v_n|/|v_t|``, an engine's
    message) as ``∣``, which does not end the cell."""
    return text.replace("|", "∣")


def grid_rows(engines: dict) -> list[tuple[str, str | None]]:
    """The grid's rows, ``(label, engine or None)``: each engine and preset in the order they
    ran (the registry's, by :func:`engine_stress`), then each engine not installed."""
    rows = dict.fromkeys(source_label(r["engine"], r["preset"]) for r in engines["runs"])
    return ([(label, None) for label in rows]
            + [(f"{name}: not installed", name) for name in engines["skipped"]])


def engine_grid_figure(engines: dict, path: Path) -> None:
    """Each engine and preset (rows) on each stress case (columns), coloured by outcome; one
    panel per shape, engines not installed as rows of their own."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.colors import ListedColormap
    from matplotlib.patches import Patch

    order = list(OUTCOME_COLOURS)
    rows = grid_rows(engines)
    labels = [label for label, _ in rows]
    shapes = list(dict.fromkeys(r["shape"] for r in engines["runs"]))
    columns = {shape: list(dict.fromkeys(case_text(r) for r in engines["runs"]
                                         if r["shape"] == shape)) for shape in shapes}
    width = max(len(names) for names in columns.values())
    figure, axes = plt.subplots(len(shapes), 1, squeeze=False,
                                figsize=(4.0 + 0.42 * width, len(shapes) * (2.6 + 0.3 * len(rows))))
    used = {"skipped"} if engines["skipped"] else set()
    for axis, shape in zip(axes[:, 0], shapes):
        grid = np.full((len(rows), len(columns[shape])), order.index("skipped"))
        for record in engines["runs"]:
            if record["shape"] != shape:
                continue
            row = labels.index(source_label(record["engine"], record["preset"]))
            grid[row, columns[shape].index(case_text(record))] = order.index(record["outcome"])
            used.add(record["outcome"])
        axis.imshow(grid, cmap=ListedColormap([OUTCOME_COLOURS[name] for name in order]),
                    vmin=-0.5, vmax=len(order) - 0.5, aspect="auto")
        axis.set_xticks(range(len(columns[shape])), columns[shape], rotation=60, ha="right",
                        rotation_mode="anchor", fontsize=9)
        axis.set_yticks(range(len(rows)), labels, fontsize=9.5)
        axis.set_xticks(np.arange(-0.5, len(columns[shape])), minor=True)
        axis.set_yticks(np.arange(-0.5, len(rows)), minor=True)
        axis.grid(which="minor", color="white", linewidth=1.0)
        axis.tick_params(which="minor", length=0)
        for row in range(1, len(rows)):  # a black rule between one engine and the next
            if rows[row][1] or labels[row].split(".")[0] != labels[row - 1].split(".")[0]:
                axis.axhline(row - 0.5, color="black", linewidth=1.2)
        axis.set_title(SHAPE_TITLES.get(shape, shape), fontsize=11)
    key = [Patch(facecolor=OUTCOME_COLOURS[name], edgecolor="grey",
                 label="not installed" if name == "skipped" else name)
           for name in order if name in used]
    figure.legend(handles=key, loc="upper right", bbox_to_anchor=(0.995, 0.99), fontsize=9,
                  title="outcome (first that applies)", title_fontsize=9, frameon=False)
    figure.suptitle("Engine stress outcomes: each engine and preset on each extreme case\n"
                    f"(each case changes one quantity of the reference: {REFERENCE_CASE})",
                    fontsize=11, x=0.02, ha="left")
    figure.tight_layout(rect=(0, 0, 0.86, 0.97))
    save_figure(figure, path, "png", dpi=120)  # over a regular file only
    plt.close(figure)


def boundary_jumps_figure(solver: dict, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    names = [b.name for b in BOUNDARIES]
    figure, axes = plt.subplots(2, 3, figsize=(12, 6.5), sharex=True, sharey=True)
    for axis, name in zip(axes.ravel(), names):
        for entry in solver["boundaries"]:
            if entry["boundary"] != name:
                continue
            deltas = np.array(entry["deltas"])
            jumps = np.array([np.nan if j is None else max(j, 1e-18)
                              for j in entry["max_jump_at_delta"]])
            axis.loglog(deltas, jumps, marker="o", markersize=3, label=entry["law"])
        axis.loglog([1e-15, 1e-2], [1e-15, 1e-2], color="grey", linestyle=":", linewidth=1,
                    label="∝ δ")
        axis.set_title(name, fontsize=10)
        axis.grid(True, which="major", alpha=0.3)
    for axis in axes[-1]:
        axis.set_xlabel("relative distance δ from the boundary")
    for axis in axes[:, 0]:
        axis.set_ylabel("max |Δ(I_n, I_t)| / (|I_n|+|I_t|)")
    axes[0, 0].legend(fontsize=8)
    figure.suptitle("Solver continuity: change of the impulses across each boundary "
                    "(continuous ⇒ → 0 with δ)")
    figure.tight_layout()
    save_figure(figure, path, "png", dpi=120)  # over a regular file only
    plt.close(figure)


def energy_figure(solver: dict, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.ticker import NullLocator

    families = [name for name in solver["families"] if name != "e-mu-extremes"]
    figure, axes = plt.subplots(1, len(families), figsize=(4 * len(families), 4.2), sharey=True)
    for axis, family in zip(np.atleast_1d(axes), families):
        for law in ("poisson", "stronge", "newton"):
            by_value = solver["families"][family][law]["max_relative_energy_change_by_parameter"]
            xs = np.array([float(k) for k in by_value])
            ys = np.array([np.nan if v is None else v for v in by_value.values()])
            axis.plot(xs, ys, marker="o", markersize=3, label=law)
        axis.set_xscale("log")
        # gains and losses from rounding (1e-16) to order one, both signs, on one axis
        axis.set_yscale("symlog", linthresh=1e-16, linscale=0.5)
        ticks = [-1.0, -1e-5, -1e-10, 0.0, 1e-10, 1e-5, 1.0]
        axis.set_yticks(ticks, ["−1", "−1e-5", "−1e-10", "0", "1e-10", "1e-5", "1"])
        axis.yaxis.set_minor_locator(NullLocator())
        axis.axhline(0.0, color="grey", linewidth=0.8)
        if family == "grazing":  # 1e-9 … 1, then 1e-100 … 1e-300: name the ends only
            axis.set_xticks([1e-300, 1e-200, 1e-100, 1.0], ["1e-300", "1e-200", "1e-100", "1"])
            axis.xaxis.set_minor_locator(NullLocator())
        axis.set_title(family)
        axis.set_xlabel({"conditioning": "Δ/(m_nn m_tt)", "mass-ratio": "mass ratio k",
                         "speed": "speed (m/s)", "grazing": "|v_n|/|v_t|",
                         "size": "size L (m)"}.get(family, family))
    np.atleast_1d(axes)[0].set_ylabel("largest ΔE / (|v_n| I_n + |v_t I_t|)\n"
                                      "(symmetric log scale, linear within ±1e-16)")
    np.atleast_1d(axes)[0].legend(fontsize=8)
    figure.suptitle("Largest energy change per stress value "
                    "(> 0 is a gain; Newton may gain, Poisson/Stronge must not)")
    figure.tight_layout()
    save_figure(figure, path, "png", dpi=120)  # over a regular file only
    plt.close(figure)


def stress_markdown(report: dict) -> str:
    solver, engines = report["solver"], report["engines"]
    lines = ["# Stress report", "",
             f"Mode: {'quick' if report['quick'] else 'full'}; "
             f"generated {report['provenance']['created_utc']}; "
             f"solver {report['timings']['solver_s']:.1f} s, "
             f"engines {report['timings']['engines_s']:.1f} s.", "",
             "## Solver", "", "| check | count |", "|---|---|"]
    for name, value in solver["totals"].items():
        lines.append(f"| {name.replace('_', ' ')} | {value} |")
    lines += ["", "Per family (rows solved / rows; silent non-finite; energy-gain rows; "
              "largest relative energy change):", "",
              "| family | law | solved | silent NaN | gain rows (beyond rounding) "
              "| gain rows > 1e-10 | max ΔE/scale |",
              "|---|---|---|---|---|---|---|"]
    for family, per_law in solver["families"].items():
        for law, summary in per_law.items():
            gain = summary["max_relative_energy_gain"]
            lines.append(f"| {family} | {law} | {summary['solved']}/{summary['rows']} | "
                         f"{summary['silent_non_finite']} | {summary['energy_gain_rows']} | "
                         f"{summary['energy_gain_rows_raw']} | "
                         f"{'—' if gain is None else f'{gain:.2e}'} |")
    scalar = solver["scalar_api"]
    lines += ["", f"Scalar `solve` on extreme bodies: {scalar['finite']} finite answers, "
              f"{scalar['error']} ImpactInputError, {scalar['silent_non_finite']} silent "
              "non-finite.", "",
              "Continuity across boundaries (max jump between neighbouring inputs ±4 ulps apart, "
              "and at relative distance δ = 1e-15 / 1e-8 / 1e-2; "
              "figure `solver-boundary-jumps.png`):", "",
              "| boundary | law | rows | max jump over ulps | δ=1e-15 | δ=1e-8 | δ=1e-2 |",
              "|---|---|---|---|---|---|---|"]

    def fmt(value):
        return "—" if value is None else f"{value:.1e}"

    for entry in solver["boundaries"]:
        at = dict(zip(entry["deltas"], entry["max_jump_at_delta"]))
        pick = [at.get(min(at, key=lambda d: abs(math.log10(d) - target)))
                for target in (-15, -8, -2)]
        lines.append(f"| {entry['boundary']} | {entry['law']} | "
                     f"{entry['rows_solved_on_both_sides']}/{entry['rows']} | "
                     f"{fmt(entry['max_ulp_jump'])} | {' | '.join(fmt(p) for p in pick)} |")
    lines += ["", "## Engines", "", "Outcomes (first that applies):", ""]
    lines += [f"- **{name}**: {text}" for name, text in OUTCOMES.items()]
    lines += ["", "| engine/preset | " + " | ".join(OUTCOMES) + " |",
              "|---|" + "---|" * len(OUTCOMES)]
    for group, counts in engines["counts"].items():
        lines.append(f"| {group} | " + " | ".join(str(counts[name]) for name in OUTCOMES) + " |")
    if engines["skipped"]:
        lines += ["", "Not installed, so not stressed (`make venv` installs every engine):", ""]
        lines += [f"- **{name}**: {reason}" for name, reason in engines["skipped"].items()]
    lines += ["", "Runs not ok:", "",
              "| engine/preset | case | outcome | status | energy ratio | penetration/extent "
              "| message |", "|---|---|---|---|---|---|---|"]
    for record in engines["runs"]:
        if record["outcome"] != "ok":
            ratio = record.get("energy_ratio")
            message = table_cell((record.get("error") or "")[:160])
            lines.append(f"| {source_label(record['engine'], record['preset'])} | "
                         f"{record['shape']}: {table_cell(case_text(record))} | "
                         f"{record['outcome']} | {record['status']} | {fmt(ratio)} | "
                         f"{fmt(record.get('max_penetration_relative'))} | {message} |")
    cache = engines["cache"]
    lines += ["", f"Engine runs: {engines['tasks_run']} simulated, {cache['hits']} from the cache "
              f"(`--no-cache` forces them).", "",
              "Figures: `engine-grid.png`, `solver-boundary-jumps.png`, "
              "`solver-energy.png`. Machine-readable: `stress.json`, `stress-engines.csv`.", ""]
    return "\n".join(lines)


def write_engine_csv(engines: dict, path: Path) -> None:
    fields = ["engine", "preset", "shape", "family", "label", "outcome", "status", "steps",
              "energy_ratio", "max_penetration_relative", "wall_time_s", "error"]
    handle = io.StringIO(newline="")  # the rows in memory, then written atomically
    writer = csv.DictWriter(handle, fieldnames=fields, extrasaction="ignore")
    writer.writeheader()
    for record in engines["runs"]:
        writer.writerow({name: record.get(name, "") for name in fields})
    write_text_atomically(path, handle.getvalue())
