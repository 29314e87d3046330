"""The Fazeli drops through the engines: each drop a scene whose body is the ellipse
(:class:`harness.scene.Ellipse`: MuJoCo's ellipsoid, elsewhere the polygon placed on its
lowest point, exact contact point and Jacobian), at the angle the published Jacobian was
evaluated at, with the ellipse's mass and inertia; every run
judged by the suite's verdicts (harness/run/verdicts/). Flagged runs are counted with
their reason, never scored; only aggregates leave this module."""

from __future__ import annotations

import numpy as np

from harness.engines import EngineNotInstalled, load_engine, preset_label
from harness.scene import Body, Ellipse, Scene, ellipse, geometry
from harness.scene.model import STAND_IN_VERTICES

from . import analysis, fazeli, metric
from .engine_curves import judged
from .records import MeasuredImpacts

VERTICES = STAND_IN_VERTICES  # the placed 8-gon's next vertex is ≥ 7.3 mm above the contact


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
    a, b = fazeli.SEMI_AXES
    _, py = ellipse.lowest_offset(theta, a, b)
    vx, vy, omega = (float(v) for v in impacts.speeds_before[row])
    body = Body("ellipse", Ellipse(a, b), fazeli.MASS, (0.0, -py), float(theta), (vx, vy),
                omega, inertia=float(impacts.mass_matrix[2, 2]))
    return Scene((geometry.place_stand_in(body),), e, mu, ground=True,
                 name=f"drop-{int(impacts.drop_ids[row])}")


def run_drops(engine, preset: str, impacts: MeasuredImpacts, thetas: np.ndarray, mu: float,
              e: float, keep_errors: bool = False, overrides: dict | None = None) -> dict:
    """Aggregates of ``engine`` under ``preset`` on every drop: verdict counts and the
    paper's normalized error of the runs judged single impacts. ``keep_errors`` adds the
    per-drop errors (NaN where flagged) as ``per_drop_errors``, for the caller to reduce:
    they must not be written anywhere. ``overrides``: the engine's own settings changed
    from the preset's (a calibration's pick), recorded in the result."""
    scenes = [drop_scene(impacts, i, float(thetas[i]), mu, e) for i in range(len(impacts))]
    runs = engine.run_many(scenes, preset=preset, overrides=overrides or None)
    verdicts = [judged(run, scene) for run, scene in zip(runs, scenes)]
    ok = np.array([v == "ok" for v in verdicts])
    after = np.array([np.asarray(run.u_after, dtype=float)[:3] for run in runs])
    errors = np.where(ok, metric.normalized_error(after, impacts.speeds_after), np.nan)
    counts: dict[str, int] = {}
    for verdict in verdicts:
        counts[verdict] = counts.get(verdict, 0) + 1
    result = {"engine": engine.name, "preset": preset, "mu": mu, "e": e,
              **({"overrides": dict(overrides)} if overrides else {}),
              "verdicts": dict(sorted(counts.items())),
              "errors": analysis.error_summary(errors)}
    if keep_errors:
        result["per_drop_errors"] = errors
    return result


#: Angles (rad) of the moment-arm measurement: every 5° over half a turn (the ellipse is
#: symmetric about its centre, so θ and θ + π are the same body on the ground).
ARM_ANGLES = tuple(np.radians(np.arange(0.0, 180.0, 5.0)).tolist())


def moment_arm_errors(engine, preset: str, angles=ARM_ANGLES) -> dict:
    """How far ``engine``'s contact point lies from the true ellipse's, per angle.

    Each angle two drops of the Fazeli ellipse (no spin, e 0.5): one frictionless (v_y
    −2.5 m/s), one sliding throughout (v (3, −1) m/s, μ 0.3: the tangential impulse a
    third of the normal one, so the height is well conditioned). The run's velocity change gives the
    impulse ``P = m Δv`` and its moment ``I Δω = p_x P_n − p_y P_t`` about the centre:
    without friction ``P_t = 0`` and the moment arm the dynamics acted through is
    ``p_x = I Δω / P_n``; with friction, given the true ``p_x``, the contact's height below
    the centre is ``p_y = (p_x P_n − I Δω) / P_t``. Both against the lowest point at the
    angle (the engine's representation and the body's turn during contact included).
    Returns per angle the errors (m) and the verdicts ("ok" or the first failing check);
    the largest errors over the single impacts and over every run.
    """
    a, b = fazeli.SEMI_AXES
    result: dict = {"engine": engine.name, "preset": preset, "angles": len(angles)}
    for label, v_x, v_y, mu in (("arm", 0.0, -2.5, 0.0), ("height", 3.0, -1.0, 0.3)):
        scenes = []
        for angle in angles:
            body = Body("ellipse", Ellipse(a, b), fazeli.MASS, (0.0, 0.0), float(angle),
                        (v_x, v_y), 0.0)
            body = geometry.place_stand_in(geometry.place_on_ground(body))
            scenes.append(Scene((body,), 0.5, mu, ground=True, name=f"{label}-{angle:.4f}"))
        errors, verdicts = [], []
        for angle, scene, run in zip(angles, scenes, engine.run_many(scenes, preset=preset)):
            body = scene.bodies[0]
            d_x, d_y, d_omega = (float(after) - float(before) for after, before
                                 in zip(run.u_after[:3], body.state()))
            moment = body.moment_of_inertia * d_omega
            p_x, p_y = ellipse.lowest_offset(float(angle), a, b)
            if label == "arm":
                errors.append(moment / (body.mass * d_y) - p_x)
            else:
                errors.append((p_x * body.mass * d_y - moment) / (body.mass * d_x) - p_y)
            verdicts.append(judged(run, scene))
        size = np.abs(np.array(errors))
        ok = np.array([v == "ok" for v in verdicts]) & np.isfinite(size)
        counts: dict[str, int] = {}
        for verdict in verdicts:
            counts[verdict] = counts.get(verdict, 0) + 1
        result[label] = {"errors": errors, "verdicts": dict(sorted(counts.items())),
                         "max_ok": float(size[ok].max()) if ok.any() else None,
                         "max_all": (float(size[np.isfinite(size)].max())
                                     if np.isfinite(size).any() else None)}
    return result


#: Errors below this (m, 0.1 µm) are rounding (doubles in pymunk, float32 in Box2D): shown
#: as a bound, so that a table does not carry a machine's last bits.
ROUNDING_LEVEL = 1e-7


def _millimetres(value: float | None) -> str:
    if value is None:
        return "—"
    return f"< {ROUNDING_LEVEL * 1e3:g}" if value < ROUNDING_LEVEL else f"{value * 1e3:.3g}"


def contact_error_table(engines) -> tuple[list[str], list[dict]]:
    """The Markdown rows of :func:`moment_arm_errors` for ``engines`` (loaded engines, or
    names loaded here; a missing engine gets a row saying so) under both presets, and the
    results."""
    rows = ["| engine | preset | moment arm | contact height | verdicts (arm drops / height "
            "drops) |", "|---|---|---:|---:|---|"]
    results = []
    for engine in engines:
        if isinstance(engine, str):
            try:
                engine = load_engine(engine)
            except EngineNotInstalled:
                rows.append(f"| {engine} | — | not installed | | |")
                continue
        name = engine.name
        for preset in ("defaults", "accurate"):
            result = moment_arm_errors(engine, preset)
            cells, counts = [], []
            for part in ("arm", "height"):
                ok, every = result[part]["max_ok"], result[part]["max_all"]
                cell = _millimetres(ok)
                if every is not None and (ok is None or every > max(ok, ROUNDING_LEVEL)):
                    cell += f" ({_millimetres(every)})"
                cells.append(cell)
                counts.append(", ".join(f"{k} {v}" for k, v in result[part]["verdicts"].items()))
            rows.append(f"| {name} | {preset_label(name, preset)} | {cells[0]} | {cells[1]} | "
                        f"{' / '.join(counts)} |")
            results.append(result)
    return rows, results
