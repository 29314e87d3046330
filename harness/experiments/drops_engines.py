"""The Fazeli drops through the engines: each drop a scene whose body is the polygon placed
on the ellipse's lowest point (``ellipse``; exact contact point and Jacobian), at the angle
the published Jacobian was evaluated at, with the ellipse's mass and inertia; every run
judged by the suite's verdicts (harness/run/verdicts.py). Flagged runs are counted with
their reason, never scored; only aggregates leave this module."""

from __future__ import annotations

import numpy as np

from . import analysis, ellipse, fazeli, metric
from .records import MeasuredImpacts

VERTICES = 8  # Box2D's most; the placed 8-gon's next vertex is ≥ 7.3 mm above the contact


def jacobian_angles(impacts: MeasuredImpacts, guess: np.ndarray,
                    span: float = 0.2) -> tuple[np.ndarray, np.ndarray]:
    """Per drop, the angle whose lowest point is the published contact (w_n[2] = p_x,
    w_t[2] = −p_y), searched within ``span`` rad of ``guess`` (two scans, the second
    1/1000 as wide), and the distance left (m)."""
    a, b = fazeli.SEMI_AXES
    target = np.stack([impacts.wn[:, 2], -impacts.wt[:, 2]], axis=1)
    centre = np.asarray(guess, dtype=float)
    for width in (span, span / 1000):
        trial = centre[:, None] + np.linspace(-width, width, 2001)[None, :]
        _, px, py = ellipse.lowest_point(trial, a, b)
        distance = np.hypot(px - target[:, :1], py - target[:, 1:])
        best = np.argmin(distance, axis=1)
        centre = trial[np.arange(trial.shape[0]), best]
    return centre, distance[np.arange(distance.shape[0]), best]


def drop_scene(impacts: MeasuredImpacts, row: int, theta: float, mu: float, e: float):
    from harness.scene.model import Body, Polygon, Scene

    a, b = fazeli.SEMI_AXES
    phi, _, py = ellipse.lowest_point(theta, a, b)
    phis = phi + 2 * np.pi * np.arange(VERTICES) / VERTICES  # increasing φ: anticlockwise
    points = tuple((float(a * np.cos(p)), float(b * np.sin(p))) for p in phis)
    vx, vy, omega = (float(v) for v in impacts.speeds_before[row])
    body = Body("ellipse", Polygon(points), fazeli.MASS, (0.0, float(-py)), float(theta),
                (vx, vy), omega, inertia=float(impacts.mass_matrix[2, 2]))
    return Scene((body,), e, mu, ground=True, name=f"drop-{int(impacts.drop_ids[row])}")


def run_drops(engine, preset: str, impacts: MeasuredImpacts, thetas: np.ndarray, mu: float,
              e: float, keep_errors: bool = False) -> dict:
    """Aggregates of ``engine`` under ``preset`` on every drop: verdict counts and the
    paper's normalized error of the runs judged single impacts. ``keep_errors`` adds the
    per-drop errors (NaN where flagged) as ``per_drop_errors``, for the caller to reduce:
    they must not be written anywhere."""
    from .engine_curves import judged

    scenes = [drop_scene(impacts, i, float(thetas[i]), mu, e) for i in range(len(impacts))]
    runs = engine.run_many(scenes, preset=preset)
    verdicts = [judged(run, scene) for run, scene in zip(runs, scenes)]
    ok = np.array([v == "ok" for v in verdicts])
    after = np.array([np.asarray(run.u_after, dtype=float)[:3] for run in runs])
    errors = np.where(ok, metric.normalized_error(after, impacts.speeds_after), np.nan)
    counts: dict[str, int] = {}
    for verdict in verdicts:
        counts[verdict] = counts.get(verdict, 0) + 1
    result = {"engine": engine.name, "preset": preset, "mu": mu, "e": e,
              "verdicts": dict(sorted(counts.items())),
              "errors": analysis.error_summary(errors)}
    if keep_errors:
        result["per_drop_errors"] = errors
    return result
