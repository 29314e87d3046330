"""``impact-harness stress``: the solver and the engines over hostile inputs.

Solver (``planar_impact.solve_batch``, every law), contact-space families:

* ``mass-ratio``   two bodies, masses 1 and k, k = 1e-6 … 1e6 (random contact geometry);
* ``speed``        |v^A| = 1e-6 … 1e4 m/s;
* ``grazing``      |v_n^A|/|v_t^A| = 1e-9 … 1, and 1e-100 … 1e-300 (α near overflow);
* ``size``         body size L = 1e-6 … 1e6 m (inertia ∝ m L², lever arms ∝ L);
* ``e-mu-extremes`` e ∈ {0, 1} × μ ∈ {0, 10};
* ``conditioning`` Δ/(m_nn m_tt) = 1e-3 … 1e-15 (nearly singular mass matrix);
* boundaries, each approached from both sides, at k ulps (``np.nextafter``) and at relative
  distances δ = 1e-15 … 1e-2: ``α = r_m``, ``α = (1+e) r_m``, ``g → 0`` (μ → m_nt/m_tt),
  ``p → 0`` (μ → −m_nt/m_tt), ``h → 0`` (μ → m_nn/m_nt), ``q → 0`` (μ → −m_nn/m_nt).

Checks: no silent NaN/inf (a row with status 0 has finite outputs; a bad row has a status);
continuity at the boundaries (the *jump*: the largest change of ``(I_n, I_t)`` between
neighbouring inputs, relative to ``|I_n| + |I_t|``, must shrink with the distance; across one
ulp it is rounding); Poisson and Stronge never gain energy (a gain above 1e-10 of the
energy scale ``|v_n| I_n + |v_t I_t|`` plus the rounding allowance ``10 eps/c`` of a problem of
conditioning ``c = Δ/(m_nn m_tt)`` is counted; raw gains above 1e-10 are reported apart). Newton's gains are counted too, as
information (Newton can gain energy; THEORY.md §4).

Engines (every installed engine, via :func:`harness.engines.load_engine`): a disk and the
45° rod against the ground, scaled in mass (1e-6 … 1e6 kg), size (1e-4 … 1e3 m), speed
(1e-6 … 1e4 m/s), near grazing, e ∈ {0, 1}, μ ∈ {0, 10}, and time steps 1e-6 … 1e-1 s.
Each run's outcome is the first that applies of: ``error`` (exception), ``non-finite``,
``blow-up``, ``energy-gain`` (kinetic energy up by more than 1e-6 relative),
``no-separation`` (step cap hit in contact), ``deep-penetration`` (deeper than 10% of the
body's extent), ``no-contact`` (never touched within the cap), ``flagged`` (multi-contact,
out-of-plane), ``ok``. Quick mode runs the ``accurate`` presets; full mode both presets over
finer sweeps. Missing engines are reported as skipped.

Outputs in ``--out`` (default ``reports/stress``): ``stress.md`` (the stability report),
``stress.json`` (everything, machine-readable), ``stress-engines.csv`` (one row per engine
run), figures ``engine-grid.png``, ``solver-boundary-jumps.png``, ``solver-energy.png``.
Engine runs are cached (:class:`harness.cache.ResultCache`; ``--no-cache`` forces them) and
spread over local cores (:func:`harness.executor.run_tasks`; ``--executor dask``).
"""

from __future__ import annotations

import csv
import json
import math
import platform
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

import planar_impact as pi
from harness.random_problems import random_problems

LAWS: tuple[str, ...] = pi.HYPOTHESES
ENERGY_LAWS: tuple[str, ...] = ("poisson", "stronge")  # must never gain energy
ENERGY_GAIN_TOLERANCE = 1e-10  # relative to |v_n| I_n + |v_t I_t|: rounding of (A29)
# Near-singular M (c = Δ/(m_nn m_tt) → 0) amplifies rounding like eps/c (measured: relative
# gains 8e-5 at c = 1e-12, 0.04 at 1e-14, 0.36 at 1e-15); that part is allowed, and reported.
CONDITIONING_ALLOWANCE = 10.0 * np.finfo(float).eps


def energy_tolerance(mnn, mnt, mtt):
    """Relative energy gain allowed by rounding for problems of conditioning ``Δ/(m_nn m_tt)``."""
    with np.errstate(all="ignore"):
        conditioning = (mnn * mtt - mnt * mnt) / (mnn * mtt)
        return ENERGY_GAIN_TOLERANCE + CONDITIONING_ALLOWANCE / np.maximum(conditioning, 1e-300)
ULP_JUMP_TOLERANCE = 1e-9  # a jump across a few ulps above this is a discontinuity
ENGINE_ENERGY_TOLERANCE = 1e-6  # relative kinetic-energy gain counted for an engine
DEEP_PENETRATION = 0.1  # of the body's extent

OUTCOMES: dict[str, str] = {
    "error": "the adapter or engine raised an exception",
    "non-finite": "NaN or infinite post-impact velocities",
    "blow-up": "kinetic-energy norm grew more than 1e3 times",
    "energy-gain": f"kinetic energy gained (> {ENGINE_ENERGY_TOLERANCE:g} relative)",
    "no-separation": "still in contact at the step cap",
    "no-contact": "the engine never saw the contact (tunnelled or missed within the cap)",
    "deep-penetration": f"penetration deeper than {DEEP_PENETRATION:g} of the body's extent",
    "flagged": "another non-ok engine status (multi-contact, out-of-plane)",
    "ok": "finite, separated, no energy gain, shallow",
}
OUTCOME_COLOURS = {"error": "#000000", "non-finite": "#7f0000", "blow-up": "#d7301f",
                   "energy-gain": "#fc8d59", "no-separation": "#fdcc8a", "no-contact": "#ffffb2",
                   "deep-penetration": "#c994c7",
                   "flagged": "#bdbdbd", "ok": "#1a9850", "skipped": "#ffffff"}


# ====================================================================== solver
def _solve_all(problems: dict, law: str):
    return pi.solve_batch(problems["mnn"], problems["mnt"], problems["mtt"], problems["vn"],
                          problems["vt"], problems["mu"], problems["e"], hypothesis=law)


def _ground_terms(mass, inertia, r_x, r_y):
    """(A20) terms of one body hit by the ground at offset (r_x, r_y): n = +y, t = +x."""
    return 1.0 / mass + r_x**2 / inertia, -r_x * r_y / inertia, 1.0 / mass + r_y**2 / inertia


def solver_families(count: int, seed: int = 0) -> dict[str, tuple[np.ndarray, dict]]:
    """Hostile contact-space problem sets: ``family -> (parameter per row, problems)``."""
    rng = np.random.default_rng(seed)
    families: dict[str, tuple[np.ndarray, dict]] = {}

    def base(n):
        return random_problems(n, seed=int(rng.integers(1 << 30)))

    # mass ratio: body B (mass k) hits body A (mass 1); random offsets, inertia m·(0.1 m)²
    ratios = 10.0 ** np.repeat(np.linspace(-6, 6, 13), count)
    n = ratios.size
    terms_a = _ground_terms(1.0, 1e-2, *rng.uniform(-0.2, 0.2, (2, n)))
    terms_b = _ground_terms(ratios, ratios * 1e-2, *rng.uniform(-0.2, 0.2, (2, n)))
    problems = base(n)
    problems.update(mnn=terms_a[0] + terms_b[0], mnt=terms_a[1] + terms_b[1], mtt=terms_a[2] + terms_b[2])
    families["mass-ratio"] = (ratios, problems)

    speeds = 10.0 ** np.repeat(np.linspace(-6, 4, 11), count)
    problems = base(speeds.size)
    direction = rng.uniform(0.02, np.pi / 2, speeds.size)
    problems.update(vn=-speeds * np.sin(direction), vt=speeds * np.cos(direction) * rng.choice([-1, 1], speeds.size))
    families["speed"] = (speeds, problems)

    # down to 1e-9 as asked, then on to the edge of the float range (α → 1e300)
    grazing = 10.0 ** np.repeat(np.concatenate([np.linspace(-9, 0, 10), [-100, -200, -300]]), count)
    problems = base(grazing.size)
    problems.update(vn=-grazing, vt=np.ones_like(grazing))
    families["grazing"] = (grazing, problems)

    sizes = 10.0 ** np.repeat(np.linspace(-6, 6, 13), count)
    offsets = rng.uniform(-0.5, 0.5, (2, sizes.size)) * sizes
    problems = base(sizes.size)
    problems.update(dict(zip(("mnn", "mnt", "mtt"), _ground_terms(1.0, sizes**2 / 12.0, *offsets))))
    families["size"] = (sizes, problems)

    problems = base(4 * count)
    corner = np.repeat(np.arange(4), count)  # (e, μ) = (0,0), (0,10), (1,0), (1,10)
    problems.update(e=np.where(corner >= 2, 1.0, 0.0), mu=np.where(corner % 2 == 1, 10.0, 0.0))
    families["e-mu-extremes"] = (corner.astype(float), problems)

    # conditioning: Δ/(m_nn m_tt) = 1 − ρ² from 1e-3 down to 1e-15 (nearly singular M)
    conditioning = 10.0 ** np.repeat(np.linspace(-15, -3, 13), count)
    problems = base(conditioning.size)
    rho = np.sqrt(1.0 - conditioning) * rng.choice([-1.0, 1.0], conditioning.size)
    problems["mnt"] = rho * np.sqrt(problems["mnn"] * problems["mtt"])
    families["conditioning"] = (conditioning, problems)
    return families


def check_rows(result, problems: dict) -> dict:
    """Counts for one law over one family: statuses, silent non-finite, energy gain."""
    outputs = np.stack([result.normal_impulse, result.tangential_impulse, result.vn_separation,
                        result.vt_separation, result.energy_change])
    solved = result.status == 0
    finite = np.all(np.isfinite(outputs), axis=0)
    scale = np.abs(problems["vn"]) * np.abs(result.normal_impulse) + np.abs(problems["vt"] * result.tangential_impulse)
    with np.errstate(invalid="ignore", divide="ignore"):
        relative_gain = np.where(solved & finite & (scale > 0), result.energy_change / scale, -np.inf)
    statuses = {pi.STATUS_MESSAGES[int(code)].split(" (")[0].split(":")[0]: int(np.sum(result.status == code))
                for code in np.unique(result.status)}
    return {
        "rows": int(result.status.size),
        "solved": int(solved.sum()),
        "statuses": statuses,
        "silent_non_finite": int(np.sum(solved & ~finite)),
        # gains beyond rounding (conditioning-aware), and any gain above 1e-10 at all
        "energy_gain_rows": int(np.sum(relative_gain > energy_tolerance(problems["mnn"], problems["mnt"],
                                                                          problems["mtt"]))),
        "energy_gain_rows_raw": int(np.sum(relative_gain > ENERGY_GAIN_TOLERANCE)),
        "max_relative_energy_gain": float(np.max(relative_gain)) if np.any(solved & finite) else None,
    }


@dataclass(frozen=True)
class Boundary:
    name: str
    parameter: str  # "vt" (α with v_n = -1) or "mu"
    description: str


BOUNDARIES: tuple[Boundary, ...] = (
    Boundary("alpha=r_m", "vt", "α = r_m: sticking in compression | restitution (Cases 1-3)"),
    Boundary("alpha=(1+e)r_m", "vt", "α = (1+e) r_m: sticking or reversal | forward sliding"),
    Boundary("g=0", "mu", "μ = m_nt/m_tt (m_nt > 0): Case 5 | Cases 1-3"),
    Boundary("p=0", "mu", "μ = −m_nt/m_tt (m_nt < 0): Case 3 | Cases 1-2"),
    Boundary("h=0", "mu", "μ = m_nn/m_nt (m_nt > 0): Case 4 | Cases 1-3"),
    Boundary("q=0", "mu", "μ = −m_nn/m_nt (m_nt < 0): Case 1-2 region edge"),
)


def boundary_problems(boundary: Boundary, count: int, seed: int) -> tuple[dict, np.ndarray]:
    """Base problems (one per row) and the boundary value of the swept parameter per row."""
    problems = random_problems(count, seed=seed)
    problems["vn"] = -np.ones(count)
    mnn, mnt, mtt = problems["mnn"], problems["mnt"], problems["mtt"]
    if boundary.name.startswith("alpha"):
        problems["mu"] = np.maximum(problems["mu"], 1e-3)
        mu = problems["mu"]
        # same expressions as laws.ContactTerms, so the boundary is hit to the bit
        r_m = (mu * mtt - mnt) / (mnn - mu * mnt)
        value = r_m if boundary.name == "alpha=r_m" else (1.0 + problems["e"]) * r_m
        keep = value > 0
    else:
        positive = boundary.name in ("g=0", "h=0")
        mnt = np.abs(mnt) if positive else -np.abs(mnt)
        mnt = np.where(mnt == 0, (1e-3 if positive else -1e-3) * np.sqrt(mnn * mtt), mnt)
        problems["mnt"] = mnt
        value = {"g=0": mnt / mtt, "p=0": -mnt / mtt, "h=0": mnn / mnt, "q=0": -mnn / mnt}[boundary.name]
        problems["vt"] = np.abs(problems["vt"]) + 0.1  # forward slip, so the sign of m_nt holds
        keep = np.isfinite(value) & (value > 0)
    problems = {name: values[keep] for name, values in problems.items()}
    return problems, value[keep]


def _with_parameter(problems: dict, parameter: str, values: np.ndarray) -> dict:
    shifted = dict(problems)
    shifted[parameter] = values
    return shifted


def _impulses(problems: dict, law: str) -> tuple[np.ndarray, np.ndarray]:
    result = _solve_all(problems, law)
    return np.stack([result.normal_impulse, result.tangential_impulse]), result.status


def boundary_jumps(boundary: Boundary, law: str, count: int, seed: int, ulps: int = 4,
                   deltas: np.ndarray | None = None) -> dict:
    """Continuity across one boundary for one law.

    * ulp scan: the parameter at ``-ulps … +ulps`` ulps of the boundary; the jump is the
      largest change of ``(I_n, I_t)`` between neighbours, over ``|I_n| + |I_t|``.
    * δ scan: the parameter at ``boundary·(1 ∓ δ)``; the change between the two sides over
      ``|I_n| + |I_t|`` (continuity: it falls in proportion to δ).
    """
    problems, value = boundary_problems(boundary, count, seed)
    grid = [value]
    for step in range(ulps):
        grid.insert(0, np.nextafter(grid[0], -np.inf))
        grid.append(np.nextafter(grid[-1], np.inf))
    impulses, statuses = [], []
    for values in grid:
        pair, status = _impulses(_with_parameter(problems, boundary.parameter, values), law)
        impulses.append(pair)
        statuses.append(status)
    stack = np.stack(impulses)  # (2·ulps+1, 2, rows)
    status_ok = np.all(np.stack(statuses) == 0, axis=0)
    scale = np.max(np.sum(np.abs(stack), axis=1), axis=0)
    steps = np.max(np.sum(np.abs(np.diff(stack, axis=0)), axis=1), axis=0)
    with np.errstate(invalid="ignore", divide="ignore"):
        ulp_jump = np.where(status_ok & (scale > 0), steps / scale, np.nan)
    deltas = np.logspace(-15, -2, 14) if deltas is None else deltas
    delta_jump = []
    for delta in deltas:
        below, status_b = _impulses(_with_parameter(problems, boundary.parameter, value * (1 - delta)), law)
        above, status_a = _impulses(_with_parameter(problems, boundary.parameter, value * (1 + delta)), law)
        ok = (status_b == 0) & (status_a == 0)
        size = np.maximum(np.sum(np.abs(below), axis=0), np.sum(np.abs(above), axis=0))
        with np.errstate(invalid="ignore", divide="ignore"):
            change = np.where(ok & (size > 0), np.sum(np.abs(above - below), axis=0) / size, np.nan)
        delta_jump.append(float(np.nanmax(change)) if np.any(np.isfinite(change)) else None)
    finite = ulp_jump[np.isfinite(ulp_jump)]
    return {
        "boundary": boundary.name,
        "law": law,
        "rows": int(value.size),
        "rows_solved_on_both_sides": int(status_ok.sum()),
        "max_ulp_jump": float(finite.max()) if finite.size else None,
        "ulp_discontinuities": int(np.sum(finite > ULP_JUMP_TOLERANCE)),
        "deltas": [float(d) for d in deltas],
        "max_jump_at_delta": delta_jump,
    }


def solver_stress(quick: bool, seed: int = 0) -> dict:
    """All solver checks; a dict (JSON-able)."""
    count = 40 if quick else 400
    report: dict = {"families": {}, "boundaries": [], "energy": {}}
    for family, (parameter, problems) in solver_families(count, seed).items():
        per_law = {}
        for law in LAWS:
            result = _solve_all(problems, law)
            summary = check_rows(result, problems)
            # the worst relative energy gain per parameter value, for the energy figure
            scale = np.abs(problems["vn"]) * np.abs(result.normal_impulse) + np.abs(
                problems["vt"] * result.tangential_impulse)
            with np.errstate(invalid="ignore", divide="ignore"):
                relative = np.where(result.status == 0, result.energy_change / scale, np.nan)
            by_value = {}
            for value in np.unique(parameter):
                chosen = relative[parameter == value]
                by_value[repr(float(value))] = float(np.nanmax(chosen)) if np.any(np.isfinite(chosen)) else None
            summary["max_relative_energy_change_by_parameter"] = by_value
            per_law[law] = summary
        report["families"][family] = per_law
    # scalar API: an extreme problem either raises ImpactInputError or returns finite numbers
    report["scalar_api"] = scalar_api_checks(quick, seed)
    boundary_count = 60 if quick else 600
    for index, boundary in enumerate(BOUNDARIES):
        for law in ("poisson", "stronge", "newton"):
            report["boundaries"].append(boundary_jumps(boundary, law, boundary_count, seed + index))
    totals = {
        "silent_non_finite": sum(s["silent_non_finite"] for f in report["families"].values() for s in f.values()),
        "energy_gain_poisson_stronge": sum(f[law]["energy_gain_rows"] for f in report["families"].values()
                                           for law in ENERGY_LAWS),
        "energy_gain_poisson_stronge_raw": sum(f[law]["energy_gain_rows_raw"] for f in report["families"].values()
                                               for law in ENERGY_LAWS),
        "energy_gain_newton": sum(f["newton"]["energy_gain_rows"] for f in report["families"].values()),
        "ulp_discontinuities": sum(b["ulp_discontinuities"] for b in report["boundaries"]),
        "scalar_silent_non_finite": report["scalar_api"]["silent_non_finite"],
    }
    report["totals"] = totals
    return report


def scalar_api_checks(quick: bool, seed: int) -> dict:
    """``planar_impact.solve`` on extreme bodies: an ImpactInputError or a finite answer."""
    rng = np.random.default_rng(seed + 99)
    count = 60 if quick else 600
    outcome = {"finite": 0, "error": 0, "silent_non_finite": 0, "examples_of_errors": []}
    for _ in range(count):
        mass = 10.0 ** rng.uniform(-12, 12)
        size = 10.0 ** rng.uniform(-8, 8)
        speed = 10.0 ** rng.uniform(-8, 6)
        body = pi.builders.PlanarBody(mass, mass * size**2 / 12.0, (0.0, 0.0),
                                      (speed * rng.normal(), -speed * 10.0 ** rng.uniform(-9, 0)),
                                      speed / size * rng.normal())
        point = (size * rng.uniform(-0.5, 0.5), -size * rng.uniform(0, 0.5))
        problem = pi.builders.rigid_body_against_ground(body, point)
        try:
            result = problem.solve(mu=float(rng.choice([0.0, 0.3, 10.0])), e=float(rng.choice([0.0, 0.5, 1.0])),
                                   hypothesis=str(rng.choice(LAWS)))
        except pi.ImpactInputError as error:
            outcome["error"] += 1
            if len(outcome["examples_of_errors"]) < 3:
                outcome["examples_of_errors"].append(str(error)[:160])
            continue
        values = [result.normal_impulse, result.tangential_impulse, result.energy_change,
                  *np.asarray(result.u_after, dtype=float)]
        if all(math.isfinite(v) for v in values):
            outcome["finite"] += 1
        else:
            outcome["silent_non_finite"] += 1
    return outcome


# ====================================================================== engines
def engine_cases(quick: bool) -> list[dict]:
    """Engine stress cases: ``{family, value, label, shape, mass, size, speed, grazing, e, mu, dt}``."""
    base = {"mass": 1.0, "size": 1.0, "speed": 1.0, "grazing": 1.0, "e": 0.5, "mu": 0.3, "dt": None}
    sweeps = {
        "mass": [1e-6, 1e-3, 1e3, 1e6],
        "size": [1e-4, 1e-2, 1e2, 1e3],
        "speed": [1e-6, 1e-3, 1e2, 1e4],
        "grazing": [1e-3, 1e-6, 1e-9],
        "e-mu": [(0.0, 0.0), (0.0, 10.0), (1.0, 0.0), (1.0, 10.0)],
        "time_step": [1e-6, 1e-4, 1e-2, 1e-1],
    }
    if not quick:
        sweeps.update(
            mass=[1e-6, 1e-4, 1e-2, 1e2, 1e4, 1e6],
            size=[1e-4, 1e-3, 1e-2, 1e-1, 1e1, 1e2, 1e3],
            speed=[1e-6, 1e-4, 1e-2, 1e1, 1e2, 1e3, 1e4],
            grazing=[1e-1, 1e-2, 1e-3, 1e-4, 1e-6, 1e-9],
            time_step=[1e-6, 1e-5, 1e-4, 1e-3, 1e-2, 3e-2, 1e-1],
        )
    cases = []
    for shape in ("disk", "rod"):
        cases.append(dict(base, family="reference", value=1.0, label="reference", shape=shape))
        for family, values in sweeps.items():
            for value in values:
                case = dict(base, family=family, shape=shape)
                if family == "e-mu":
                    case.update(e=value[0], mu=value[1], value=list(value), label=f"e={value[0]:g},mu={value[1]:g}")
                else:
                    key = {"time_step": "dt"}.get(family, family)
                    case.update({key: value, "value": value, "label": f"{family}={value:g}"})
                cases.append(case)
    return cases


def build_scene(case: dict):
    """The stressed scene: a disk (r 0.1·size) or the 45° rod (1·size) on the ground."""
    from harness.scene import Body, Disk, Rod, Scene

    size, mass, speed = case["size"], case["mass"], case["speed"]
    # approach direction: |v_n|/|v_t| = grazing ratio (1 = 45°)
    vn = -speed * case["grazing"] / math.hypot(1.0, case["grazing"])
    vt = speed / math.hypot(1.0, case["grazing"])
    if case["shape"] == "disk":
        radius = 0.1 * size
        body = Body("disk", Disk(radius), mass, (0.0, radius), 0.0, (vt, vn), 0.0)
    else:
        angle, length, cap = math.radians(45.0), 1.0 * size, 0.005 * size
        low_y = -length / 2.0 * math.sin(angle)
        body = Body("rod", Rod(length, cap), mass, (0.0, -low_y + cap), angle, (vt, vn), 0.0,
                    inertia=mass * length**2 / 12.0)
    return Scene((body,), case["e"], case["mu"], ground=True, name=f"{case['shape']}:{case['label']}")


def _outcome(run, scene, extent: float) -> str:
    from harness.engines import ke_norm

    u_after = np.asarray(run.u_after, dtype=float)
    if not np.all(np.isfinite(u_after)):
        return "non-finite"
    if run.status == "blow-up":
        return "blow-up"
    before, after = ke_norm(scene, scene.state()), ke_norm(scene, u_after)
    if after**2 > before**2 * (1.0 + ENGINE_ENERGY_TOLERANCE):
        return "energy-gain"
    if run.status == "no-separation":
        return "no-separation"
    if run.max_penetration > DEEP_PENETRATION * extent:
        return "deep-penetration"
    if run.status == "no-contact":
        return "no-contact"
    if run.status != "ok":
        return "flagged"
    return "ok"


def run_engine_case(task: dict) -> dict:
    """One engine stress run (top-level: runs in worker processes)."""
    from harness.engines import body_extent, ke_norm, load_engine

    case, engine_name, preset = task["case"], task["engine"], task["preset"]
    scene = build_scene(case)
    record = {"engine": engine_name, "preset": preset, "shape": case["shape"], "family": case["family"],
              "label": case["label"], "value": case["value"]}
    try:
        engine = load_engine(engine_name)
        overrides = {"time_step": case["dt"]} if case["dt"] is not None else None
        if overrides and engine_name == "mujoco" and preset == "accurate":
            # MuJoCo's accurate preset ties the contact's duration to steps: keep its spring
            # fixed at the preset's 0.5 ms contact so the time step is what changes
            overrides["contact_steps"] = max(1, int(round(5e-4 / case["dt"])))
        settings = engine.settings(preset, overrides)
        run = engine.run(scene, settings)
    except Exception as error:  # noqa: BLE001 - any failure is an outcome to report
        record.update(outcome="error", status="error", error=f"{type(error).__name__}: {error}"[:300])
        return record
    extent = body_extent(scene.bodies[0].shape)
    u_before = scene.state()
    u_after = np.asarray(run.u_after, dtype=float)
    before = ke_norm(scene, u_before)
    with np.errstate(all="ignore"):
        energy_ratio = (ke_norm(scene, u_after) / before) ** 2 if np.all(np.isfinite(u_after)) else None
    record.update(
        outcome=_outcome(run, scene, extent),
        status=run.status,
        steps=run.steps,
        max_penetration_relative=run.max_penetration / extent,
        energy_ratio=energy_ratio,
        u_after=[float(v) for v in u_after],
        engine_version=run.engine_version,
        wall_time_s=run.wall_time_s,
    )
    return record


def engine_stress(quick: bool, executor: str = "local", workers: int | None = None,
                  scheduler: str | None = None, use_cache: bool = True,
                  cache_root: Path = Path(".cache/results"), progress=None) -> dict:
    """All engine runs (cached), grouped; JSON-able."""
    from harness.cache import ResultCache
    from harness.engines import ENGINE_NAMES, EngineNotInstalled, load_engine
    from harness.executor import run_tasks

    presets = ("accurate",) if quick else ("defaults", "accurate")
    skipped, versions = {}, {}
    for name in ENGINE_NAMES:
        try:
            versions[name] = load_engine(name).version
        except EngineNotInstalled as error:
            skipped[name] = str(error)
    cases = engine_cases(quick)
    tasks = [{"case": case, "engine": name, "preset": preset}
             for name in versions for preset in presets for case in cases]
    cache = ResultCache(cache_root, enabled=use_cache)
    keys = [cache.key({"kind": "stress-engine", "task": task, "engine_version": versions[task["engine"]]})
            for task in tasks]
    records: list[dict | None] = [cache.get(key) for key in keys]
    todo = [index for index, record in enumerate(records) if record is None]
    started = time.perf_counter()
    fresh = run_tasks(run_engine_case, [tasks[i] for i in todo], executor=executor, workers=workers,
                      scheduler=scheduler, progress=progress)
    for index, record in zip(todo, fresh):
        records[index] = record
        if record["outcome"] != "error" or "not installed" not in record.get("error", ""):
            cache.put(keys[index], record)
    counts: dict = {}
    for record in records:
        group = counts.setdefault(f"{record['engine']}/{record['preset']}", {name: 0 for name in OUTCOMES})
        group[record["outcome"]] += 1
    return {"versions": versions, "skipped": skipped, "presets": list(presets), "runs": records,
            "counts": counts, "cache": cache.stats, "engine_seconds": time.perf_counter() - started,
            "tasks_run": len(todo)}


# ====================================================================== outputs
def _figure_engine_grid(engines: dict, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.colors import ListedColormap
    from matplotlib.patches import Patch

    order = list(OUTCOME_COLOURS)
    rows = sorted({f"{r['engine']}/{r['preset']}" for r in engines["runs"]})
    rows += [f"{name} (skipped)" for name in engines["skipped"]]
    columns = []
    for record in engines["runs"]:
        column = f"{record['shape']}: {record['label']}"
        if column not in columns:
            columns.append(column)
    grid = np.full((len(rows), len(columns)), order.index("skipped"))
    for record in engines["runs"]:
        grid[rows.index(f"{record['engine']}/{record['preset']}"),
             columns.index(f"{record['shape']}: {record['label']}")] = order.index(record["outcome"])
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
    axes.legend(handles=[Patch(facecolor=OUTCOME_COLOURS[n], edgecolor="grey", label=n) for n in used],
                loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8)
    axes.set_title("Engine stress outcomes (engine/preset × stress case)")
    figure.tight_layout()
    figure.savefig(path, dpi=120)
    plt.close(figure)


def _figure_boundaries(solver: dict, path: Path) -> None:
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
            jumps = np.array([np.nan if j is None else max(j, 1e-18) for j in entry["max_jump_at_delta"]])
            axis.loglog(deltas, jumps, marker="o", markersize=3, label=entry["law"])
        axis.loglog([1e-15, 1e-2], [1e-15, 1e-2], color="grey", linestyle=":", linewidth=1, label="∝ δ")
        axis.set_title(name, fontsize=10)
        axis.grid(True, which="major", alpha=0.3)
    for axis in axes[-1]:
        axis.set_xlabel("relative distance δ from the boundary")
    for axis in axes[:, 0]:
        axis.set_ylabel("max |Δ(I_n, I_t)| / (|I_n|+|I_t|)")
    axes[0, 0].legend(fontsize=8)
    figure.suptitle("Solver continuity: change of the impulses across each boundary (continuous ⇒ → 0 with δ)")
    figure.tight_layout()
    figure.savefig(path, dpi=120)
    plt.close(figure)


def _figure_energy(solver: dict, path: Path) -> None:
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
            axis.semilogx(xs, np.sign(ys) * np.log10(1 + np.abs(ys) / 1e-16), marker="o", markersize=3, label=law)
        axis.axhline(0.0, color="grey", linewidth=0.8)
        axis.set_title(family)
        axis.set_xlabel({"conditioning": "Δ/(m_nn m_tt)", "mass-ratio": "mass ratio k", "speed": "speed (m/s)", "grazing": "|v_n|/|v_t|",
                         "size": "size L (m)"}.get(family, family))
    np.atleast_1d(axes)[0].set_ylabel("max ΔE / (|v_n|I_n+|v_t I_t|)\nsign·log10(1+|x|/1e-16)")
    np.atleast_1d(axes)[0].legend(fontsize=8)
    figure.suptitle("Largest energy change per stress value (> 0 is a gain; Newton may gain, Poisson/Stronge must not)")
    figure.tight_layout()
    figure.savefig(path, dpi=120)
    plt.close(figure)


def _markdown(report: dict) -> str:
    solver, engines = report["solver"], report["engines"]
    lines = ["# Stress report", "",
             f"Mode: {'quick' if report['quick'] else 'full'}; generated {report['provenance']['time']}; "
             f"solver {report['timings']['solver_s']:.1f} s, engines {report['timings']['engines_s']:.1f} s.", "",
             "## Solver", "", "| check | count |", "|---|---|"]
    for name, value in solver["totals"].items():
        lines.append(f"| {name.replace('_', ' ')} | {value} |")
    lines += ["", "Per family (rows solved / rows; silent non-finite; energy-gain rows; largest relative "
              "energy change):", "", "| family | law | solved | silent NaN | gain rows (beyond rounding) | gain rows > 1e-10 | max ΔE/scale |",
              "|---|---|---|---|---|---|---|"]
    for family, per_law in solver["families"].items():
        for law, summary in per_law.items():
            gain = summary["max_relative_energy_gain"]
            lines.append(f"| {family} | {law} | {summary['solved']}/{summary['rows']} | "
                         f"{summary['silent_non_finite']} | {summary['energy_gain_rows']} | {summary['energy_gain_rows_raw']} | "
                         f"{'—' if gain is None else f'{gain:.2e}'} |")
    scalar = solver["scalar_api"]
    lines += ["", f"Scalar `solve` on extreme bodies: {scalar['finite']} finite answers, {scalar['error']} "
              f"ImpactInputError, {scalar['silent_non_finite']} silent non-finite.", "",
              "Continuity across boundaries (max jump between neighbouring inputs ±4 ulps apart, and "
              "at relative distance δ = 1e-15 / 1e-8 / 1e-2; figure `solver-boundary-jumps.png`):", "",
              "| boundary | law | rows | max jump over ulps | δ=1e-15 | δ=1e-8 | δ=1e-2 |", "|---|---|---|---|---|---|---|"]

    def fmt(value):
        return "—" if value is None else f"{value:.1e}"

    for entry in solver["boundaries"]:
        at = dict(zip(entry["deltas"], entry["max_jump_at_delta"]))
        pick = [at.get(min(at, key=lambda d: abs(math.log10(d) - target))) for target in (-15, -8, -2)]
        lines.append(f"| {entry['boundary']} | {entry['law']} | {entry['rows_solved_on_both_sides']}/{entry['rows']} | "
                     f"{fmt(entry['max_ulp_jump'])} | {' | '.join(fmt(p) for p in pick)} |")
    lines += ["", "## Engines", "", "Outcomes (first that applies):", ""]
    lines += [f"- **{name}**: {text}" for name, text in OUTCOMES.items()]
    lines += ["", "| engine/preset | " + " | ".join(OUTCOMES) + " |", "|---|" + "---|" * len(OUTCOMES)]
    for group, counts in engines["counts"].items():
        lines.append(f"| {group} | " + " | ".join(str(counts[name]) for name in OUTCOMES) + " |")
    for name, reason in engines["skipped"].items():
        lines.append(f"| {name} | skipped: {reason} |")
    lines += ["", "Runs not ok:", "", "| engine/preset | case | outcome | status | energy ratio | penetration/extent |",
              "|---|---|---|---|---|---|"]
    for record in engines["runs"]:
        if record["outcome"] != "ok":
            ratio = record.get("energy_ratio")
            lines.append(f"| {record['engine']}/{record['preset']} | {record['shape']}: {record['label']} | "
                         f"{record['outcome']} | {record['status']} | {fmt(ratio)} | "
                         f"{fmt(record.get('max_penetration_relative'))} |"
                         + (f" {record['error'][:120]}" if record.get("error") else ""))
    cache = engines["cache"]
    lines += ["", f"Engine runs: {engines['tasks_run']} simulated, {cache['hits']} from the cache "
              f"(`--no-cache` forces them).", "", "Figures: `engine-grid.png`, `solver-boundary-jumps.png`, "
              "`solver-energy.png`. Machine-readable: `stress.json`, `stress-engines.csv`.", ""]
    return "\n".join(lines)


def _write_csv(engines: dict, path: Path) -> None:
    fields = ["engine", "preset", "shape", "family", "label", "outcome", "status", "steps",
              "energy_ratio", "max_penetration_relative", "wall_time_s", "error"]
    with open(path, "w", newline="") as handle:
        writer = csv.DictWriter(handle, fieldnames=fields, extrasaction="ignore")
        writer.writeheader()
        for record in engines["runs"]:
            writer.writerow({name: record.get(name, "") for name in fields})


def run(quick: bool, out_dir: Path, executor: str = "local", workers: int | None = None,
        scheduler: str | None = None, use_cache: bool = True, engines: bool = True) -> dict:
    """The whole stress test; writes the report into ``out_dir`` and returns it."""
    from harness.executor import progress_printer

    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    started = time.perf_counter()
    solver = solver_stress(quick)
    solver_s = time.perf_counter() - started
    started = time.perf_counter()
    if engines:
        engine_report = engine_stress(quick, executor, workers, scheduler, use_cache,
                                      progress=None if quick else progress_printer("stress engines"))
    else:
        engine_report = {"versions": {}, "skipped": {}, "presets": [], "runs": [], "counts": {},
                         "cache": {"hits": 0, "misses": 0}, "tasks_run": 0}
    engines_s = time.perf_counter() - started
    report = {
        "format": 1,
        "quick": quick,
        "provenance": {"python": platform.python_version(), "numpy": np.__version__,
                       "machine": platform.machine(), "time": time.strftime("%Y-%m-%dT%H:%M:%S"),
                       "engine_versions": engine_report["versions"], "executor": executor},
        "timings": {"solver_s": solver_s, "engines_s": engines_s},
        "solver": solver,
        "engines": engine_report,
    }
    (out_dir / "stress.json").write_text(json.dumps(report, indent=1, default=str))
    _write_csv(engine_report, out_dir / "stress-engines.csv")
    _figure_boundaries(solver, out_dir / "solver-boundary-jumps.png")
    _figure_energy(solver, out_dir / "solver-energy.png")
    if engine_report["runs"]:
        _figure_engine_grid(engine_report, out_dir / "engine-grid.png")
    (out_dir / "stress.md").write_text(_markdown(report))
    return report


def add_arguments(parser) -> None:
    parser.add_argument("--quick", action="store_true", help="fewer cases; finishes in about a minute")
    parser.add_argument("--out", type=Path, default=Path("reports/stress"), help="output directory")
    parser.add_argument("--executor", choices=("local", "dask"), default="local",
                        help="where engine runs execute (default: a local process pool)")
    parser.add_argument("--workers", type=int, default=None, help="worker processes (default: all cores)")
    parser.add_argument("--scheduler", default=None, help="Dask scheduler address (with --executor dask)")
    parser.add_argument("--no-cache", action="store_true", help="rerun every engine case")
    parser.add_argument("--solver-only", action="store_true", help="skip the engines")


def main(args) -> int:
    started = time.perf_counter()
    report = run(args.quick, args.out, executor=args.executor, workers=args.workers,
                 scheduler=args.scheduler, use_cache=not args.no_cache, engines=not args.solver_only)
    totals = report["solver"]["totals"]
    print(f"solver: {totals}")
    for group, counts in report["engines"]["counts"].items():
        bad = {name: count for name, count in counts.items() if count and name != "ok"}
        print(f"{group}: ok {counts['ok']}, {bad or 'no failures'}")
    for name, reason in report["engines"]["skipped"].items():
        print(f"{name}: skipped ({reason})")
    print(f"written {args.out / 'stress.md'} ({time.perf_counter() - started:.1f} s)")
    # exit status: the solver's guarantees (engines' failures are findings, not errors)
    failed = totals["silent_non_finite"] or totals["energy_gain_poisson_stronge"] or totals["scalar_silent_non_finite"]
    return 1 if failed else 0
