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


def engine_grid_figure(engines: dict, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.colors import ListedColormap
    from matplotlib.patches import Patch

    order = list(OUTCOME_COLOURS)
    rows = sorted({source_label(r['engine'], r['preset']) for r in engines["runs"]})
    rows += [f"{name} (skipped)" for name in engines["skipped"]]
    columns = []
    for record in engines["runs"]:
        column = f"{record['shape']}: {record['label']}"
        if column not in columns:
            columns.append(column)
    grid = np.full((len(rows), len(columns)), order.index("skipped"))
    for record in engines["runs"]:
        row_index = rows.index(source_label(record['engine'], record['preset']))
        column_index = columns.index(f"{record['shape']}: {record['label']}")
        grid[row_index, column_index] = order.index(record["outcome"])
    figure, axes = plt.subplots(figsize=(max(8, 0.32 * len(columns) + 3), 1.0 + 0.45 * len(rows)))
    axes.imshow(grid, cmap=ListedColormap([OUTCOME_COLOURS[name] for name in order]), vmin=-0.5,
                vmax=len(order) - 0.5, aspect="auto")
    axes.set_xticks(range(len(columns)), columns, rotation=90, fontsize=7)
    axes.set_yticks(range(len(rows)), rows, fontsize=8)
    axes.set_xticks(np.arange(-0.5, len(columns)), minor=True)
    axes.set_yticks(np.arange(-0.5, len(rows)), minor=True)
    axes.grid(which="minor", color="white", linewidth=0.8)
    axes.tick_params(which="minor", length=0)
    used = sorted({order[v] for v in grid.ravel()}, key=order.index)
    axes.legend(handles=[Patch(facecolor=OUTCOME_COLOURS[n], edgecolor="grey", label=n)
                         for n in used],
                loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8)
    axes.set_title("Engine stress outcomes (engine/preset × stress case)")
    figure.tight_layout()
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

    families = [name for name in solver["families"] if name != "e-mu-extremes"]
    figure, axes = plt.subplots(1, len(families), figsize=(4 * len(families), 3.6), sharey=True)
    for axis, family in zip(np.atleast_1d(axes), families):
        for law in ("poisson", "stronge", "newton"):
            by_value = solver["families"][family][law]["max_relative_energy_change_by_parameter"]
            xs = np.array([float(k) for k in by_value])
            ys = np.array([np.nan if v is None else v for v in by_value.values()])
            # symmetric log: sign(y)·log10(1 + |y|/1e-16)
            axis.semilogx(xs, np.sign(ys) * np.log10(1 + np.abs(ys) / 1e-16), marker="o",
                          markersize=3, label=law)
        axis.axhline(0.0, color="grey", linewidth=0.8)
        axis.set_title(family)
        axis.set_xlabel({"conditioning": "Δ/(m_nn m_tt)", "mass-ratio": "mass ratio k",
                         "speed": "speed (m/s)", "grazing": "|v_n|/|v_t|",
                         "size": "size L (m)"}.get(family, family))
    np.atleast_1d(axes)[0].set_ylabel("max ΔE / (|v_n|I_n+|v_t I_t|)\nsign·log10(1+|x|/1e-16)")
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
    for name, reason in engines["skipped"].items():
        lines.append(f"| {name} | skipped: {reason} |")
    lines += ["", "Runs not ok:", "",
              "| engine/preset | case | outcome | status | energy ratio | penetration/extent |",
              "|---|---|---|---|---|---|"]
    for record in engines["runs"]:
        if record["outcome"] != "ok":
            ratio = record.get("energy_ratio")
            lines.append(f"| {source_label(record['engine'], record['preset'])} | "
                         f"{record['shape']}: {record['label']} | "
                         f"{record['outcome']} | {record['status']} | {fmt(ratio)} | "
                         f"{fmt(record.get('max_penetration_relative'))} |"
                         + (f" {record['error'][:120]}" if record.get("error") else ""))
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
