"""Metrics comparing engines with the laws: departures, contact velocities, the split.

Departure (the one error measure of the harness)
    ``departure(u, u_law) = ‖u − u_law‖_M / s`` with ``‖x‖_M = sqrt(xᵀ M x)``, ``M`` the
    scene's mass matrix and ``s`` the frame-free speed scale of the input
    (:func:`frame_free_scale`): ``‖u_before‖_M`` in the ground's frame when there is ground,
    ``‖u_before − u_cm‖_M`` in the centre-of-mass frame of two free bodies. It is the
    relative error of the post-impact speeds in the kinetic-energy norm: independent of
    units, of the body's size, of a common velocity added to every free body and of turning
    the scene; 0 for an exact match and about 1 when the post-impact motion is as wrong as
    the motion itself (docs/verdicts.md, 'A frame-free departure').

The split
    An engine departs from Poisson for two reasons (docs/engines.md, 'The engine contract'):
    the law it solves, and how well it solves it. For sequential-impulse engines the law is
    ``newton-lcp`` (restitution as a target on ``v_n``, Coulomb friction at the end state), so

    * ``law_part = departure(u_newton_lcp, u_poisson)`` -- the law's own distance from
      Poisson (a property of the scenario, the same for every engine);
    * ``solve_part = departure(u_engine, u_newton_lcp)`` -- how well the engine solves it;
    * ``total = departure(u_engine, u_poisson) ≤ law_part + solve_part`` (triangle inequality).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence

import numpy as np

#: Slip speed, relative to the approach speed, below which an end state counts as sticking
#: when an engine record is classified (engines reaching their law stick to ~1e-12).
STICK_TOLERANCE = 1e-6


#: Departures of at least this many percent are written as decimals (``0.00812%``), smaller
#: ones in scientific notation (``2e-05%``): agreement to round-off reads as such, and one
#: cut-off keeps a column from mixing ``8e-03%`` with ``0.0118%``.
SCIENTIFIC_BELOW_PERCENT = 0.001

def _is_missing(value) -> bool:
    return value is None or (isinstance(value, float) and not math.isfinite(value))


def _below_cutoff(percent: float) -> bool:
    return abs(percent) < SCIENTIFIC_BELOW_PERCENT


def _scientific(percent: float) -> str:
    """``percent``, below the cut-off, in scientific notation with one digit (round-off
    level, as ``2e-05%``); a value that rounds up to the cut-off is written as it,
    ``0.001%``."""
    rounded = f"{percent:.0e}"
    if abs(float(rounded)) >= SCIENTIFIC_BELOW_PERCENT:  # 0.00095% -> 0.001%
        return f"{float(rounded):g}%"
    return f"{rounded}%"


def fmt_departure(value) -> str:
    """A departure as every page shows it, in percent with its unit even at zero: ``20.7%``,
    ``0.18%``, ``0.00812%`` (decimals down to :data:`SCIENTIFIC_BELOW_PERCENT`), ``2e-12%``
    below it, ``0%``; ``n/a`` where there is none."""
    if _is_missing(value):
        return "n/a"
    percent = 100.0 * float(value)
    if percent == 0:
        return "0%"
    if _below_cutoff(percent):
        return _scientific(percent)
    return f"{percent:.3g}%"


def fmt_departures(values: Sequence) -> list[str]:
    """Departures read together (a quantile and its interval), each as :func:`fmt_departure`
    writes it: a number reads the same wherever it stands, so that a row holding a median
    beside its interval and the same median alone never writes it two ways (``1.19e-02%
    [5e-09%, 9.31e-02%]`` beside ``0.0119%`` read as two numbers). Zero stays ``0%``, a
    missing one ``n/a``."""
    return [fmt_departure(v) for v in values]


def ke_norm(mass_matrix: np.ndarray, u: Sequence[float] | np.ndarray) -> float:
    """``sqrt(uᵀ M u)``, the kinetic-energy norm (``sqrt(2 E)``)."""
    u = np.asarray(u, dtype=float)
    return math.sqrt(max(float(u @ np.asarray(mass_matrix, dtype=float) @ u), 0.0))


def frame_free_scale(mass_matrix, u_before, *, free_bodies: bool = False) -> float:
    """The kinetic-energy norm of ``u_before`` in the frame the impact defines.

    ``free_bodies=False`` (a body against the fixed ground, or a generalised system): the
    ground's frame, ``‖u_before‖_M``. ``free_bodies=True`` (``u = (v_x, v_y, ω)`` per free
    body, no ground): the centre of mass's frame, ``‖u_before − P u_before‖_M`` with ``P``
    the ``M``-orthogonal projection on the common translations ``T_x = (1, 0, 0, 1, 0, 0…)``,
    ``T_y = (0, 1, 0, 0, 1, 0…)``, ``P = T (Tᵀ M T)⁻¹ Tᵀ M`` (it subtracts the centre of
    mass's velocity from every body). That is ``sqrt(2 E_cm)``, unchanged by a velocity added
    to every body (Galilean) and by turning the scene (``M`` weighs x and y alike).
    """
    u = np.asarray(u_before, dtype=float)
    mass_matrix = np.asarray(mass_matrix, dtype=float)
    # A record asks for the scale of the same input once per departure and per contact
    # step: the last answer is kept, keyed by the very bits of the input.
    global _last_scale
    key = (mass_matrix.shape, mass_matrix.tobytes(), u.shape, u.tobytes(), bool(free_bodies))
    last = _last_scale
    if last is not None and last[0] == key:
        return last[1]
    scale = _frame_free_scale(mass_matrix, u, free_bodies)
    _last_scale = (key, scale)
    return scale


def _frame_free_scale(mass_matrix: np.ndarray, u: np.ndarray, free_bodies: bool) -> float:
    """:func:`frame_free_scale` of float arrays, worked out."""
    if not free_bodies:
        return ke_norm(mass_matrix, u)
    translations = np.zeros((len(u), 2))
    translations[0::3, 0] = 1.0
    translations[1::3, 1] = 1.0
    weighted = translations.T @ mass_matrix  # Tᵀ M
    common = translations @ np.linalg.solve(weighted @ translations, weighted @ u)
    return ke_norm(mass_matrix, u - common)


def departure(mass_matrix, u, u_law, u_before, *, free_bodies: bool = False) -> float:
    """``‖u − u_law‖_M / frame_free_scale(u_before)``; NaN when either speed vector is
    missing or non-finite."""
    if u is None or u_law is None:
        return math.nan
    u, u_law = np.asarray(u, dtype=float), np.asarray(u_law, dtype=float)
    # The same test as np.isfinite(x).all(), a few times cheaper on a few speeds.
    if not (all(map(math.isfinite, u.tolist())) and all(map(math.isfinite, u_law.tolist()))):
        return math.nan
    scale = frame_free_scale(mass_matrix, u_before, free_bodies=free_bodies)
    return ke_norm(mass_matrix, u - u_law) / scale if scale > 0 else math.nan


def departure_batch(mass, u, u_law, u_before, *, free_bodies=False) -> np.ndarray:
    """:func:`departure` of every row at once: ``(n,)`` departures.

    ``mass`` is ``(n, k, k)`` mass matrices or ``(n, k)`` their diagonals; ``u``, ``u_law``,
    ``u_before`` are ``(n, k)``; ``free_bodies`` a bool or an ``(n,)`` bool array (the
    frame of each row, as in :func:`frame_free_scale`). A row is NaN where :func:`departure`
    is: non-finite speeds, or a zero scale. Rows padded with zero speeds (and any positive
    mass) give the departure of their leading speeds, when they are not ``free_bodies``
    rows (the centre of mass would count the padding as bodies). Many departures from the
    same rows: :class:`RowScales` computes their scales once.
    """
    return RowScales(mass, u_before, free_bodies=free_bodies).departures(u, u_law)


class RowScales:
    """The mass matrices and frame-free scales of ``n`` rows (:func:`departure_batch`'s
    arguments ``mass``, ``u_before``, ``free_bodies``), for many departures of those rows."""

    def __init__(self, mass, u_before, *, free_bodies=False) -> None:
        u_before = np.asarray(u_before, dtype=float)
        mass = np.asarray(mass, dtype=float)
        rows, size = u_before.shape
        if mass.ndim == 2:
            mass = mass[:, :, None] * np.eye(size)
        free = np.broadcast_to(np.asarray(free_bodies, dtype=bool), (rows,))
        relative = u_before
        if free.any():  # the centre of mass's frame, as frame_free_scale
            translations = np.zeros((size, 2))
            translations[0::3, 0] = 1.0
            translations[1::3, 1] = 1.0
            weighted = np.einsum("ka,nkj->naj", translations, mass[free])  # Tᵀ M
            common = np.linalg.solve(weighted @ translations,
                                     weighted @ u_before[free][:, :, None])[:, :, 0]
            relative = u_before.copy()
            relative[free] -= common @ translations.T
        self.mass = mass  # (n, k, k)
        self.scale = _ke_norms(mass, relative)  # (n,)

    def departures(self, u, u_law) -> np.ndarray:
        """``(n,)`` departures of ``u`` from ``u_law`` (both ``(n, k)``)."""
        u, u_law = np.asarray(u, dtype=float), np.asarray(u_law, dtype=float)
        difference = _ke_norms(self.mass, u - u_law)
        finite = np.all(np.isfinite(u), axis=1) & np.all(np.isfinite(u_law), axis=1)
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.where(finite & (self.scale > 0), difference / self.scale, math.nan)


def _ke_norms(mass: np.ndarray, u: np.ndarray) -> np.ndarray:
    """``sqrt(max(uᵀ M u, 0))`` per row (:func:`ke_norm` of every row)."""
    return np.sqrt(np.maximum(np.einsum("ni,nij,nj->n", u, mass, u), 0.0))


def departures(mass_matrix, u, law_speeds: Mapping[str, object], u_before, *,
               free_bodies: bool = False) -> dict[str, float]:
    """``{law: departure(u, u_law)}`` for every law that was solved.

    The same values, bit for bit, as :func:`departure` law by law (a run asks for some
    270,000): what the laws share (``u``, its finiteness, the scale) is worked out once, and
    the laws' ``(u − u_law)ᵀ M (u − u_law)`` as stacks of the very products
    :func:`ke_norm` makes, one ``1×k`` by ``k×k`` then one ``1×k`` by ``k×1`` per law (numpy's
    stacked matmul runs the same inner product per entry of the stack).
    """
    solved = [(law, u_law) for law, u_law in law_speeds.items() if u_law is not None]
    if u is None:
        return {law: math.nan for law, _ in solved}
    u = np.asarray(u, dtype=float)
    if not solved or not all(map(math.isfinite, u.tolist())):
        return {law: math.nan for law, _ in solved}
    scale = frame_free_scale(mass_matrix, u_before, free_bodies=free_bodies)
    mass_matrix = np.asarray(mass_matrix, dtype=float)
    rows = [np.asarray(u_law, dtype=float) for _, u_law in solved]
    if (u.ndim == 1 and mass_matrix.shape == (len(u), len(u))
            and all(row.shape == u.shape for row in rows)):
        stack = np.array(rows)
        if scale > 0 and all(map(math.isfinite, stack.ravel().tolist())):
            differences = u - stack
            squares = ((differences[:, None, :] @ mass_matrix)
                       @ differences[:, :, None])[:, 0, 0].tolist()
            return {law: math.sqrt(max(square, 0.0)) / scale
                    for (law, _), square in zip(solved, squares)}
    # a law's speeds not finite, a zero scale or unusual shapes: law by law
    return {law: departure(mass_matrix, u, u_law, u_before, free_bodies=free_bodies)
            for law, u_law in solved}


def energy_change(mass_matrix, u_before, u_after) -> float:
    """``½ u_afterᵀ M u_after − ½ u_beforeᵀ M u_before`` (J)."""
    return 0.5 * (ke_norm(mass_matrix, u_after) ** 2 - ke_norm(mass_matrix, u_before) ** 2)


def contact_velocities(problem, u) -> tuple[float, float]:
    """``(v_n, v_t) = (w_n·u, w_t·u)``: the contact's normal and tangential velocity (m/s)."""
    u = np.asarray(u, dtype=float)
    return float(problem.wn @ u), float(problem.wt @ u)


def delassus(problem) -> tuple[float, float, float]:
    """``(m_nn, m_nt, m_tt)`` of (A20)."""
    global _last_delassus
    mass_matrix, wn, wt = problem.mass_matrix, problem.wn, problem.wt
    # Asked again for the same problem by the record, its verdict and every contact step:
    # the last answer is kept, keyed by the very bits (and types) of the inputs.
    key = tuple((type(a), getattr(a, "dtype", None), np.shape(a), np.asarray(a).tobytes())
                for a in (mass_matrix, wn, wt))
    last = _last_delassus
    if last is not None and last[0] == key:
        return last[1]
    inverse_w = np.linalg.solve(mass_matrix, np.stack([wn, wt], axis=1))
    wn_inv, wt_inv = inverse_w[:, 0], inverse_w[:, 1]
    found = float(wn @ wn_inv), float(wn @ wt_inv), float(wt @ wt_inv)
    _last_delassus = (key, found)
    return found


#: The last (inputs, answer) of :func:`frame_free_scale` and of :func:`delassus`.
_last_scale: tuple | None = None
_last_delassus: tuple | None = None


def impulses_from_velocities(problem, u_after, *,
                             free_bodies: bool = False) -> tuple[float, float, float]:
    """The contact impulse ``(I_n, I_t)`` that best explains ``u_after``, and the residual.

    From (A22)/(A23): ``[[m_nn, m_nt], [m_nt, m_tt]] (I_n, I_t) = (Δv_n, Δv_t)``. The residual
    ``‖Δu − M⁻¹(w_n I_n + w_t I_t)‖_M`` over the frame-free scale of ``u_before`` is 0 when
    the change of speeds is a single contact impulse at the contact point (it is not when an
    engine's configuration moved during the impact, or a second point touched).
    """
    u_after = np.asarray(u_after, dtype=float)
    delta_u = u_after - problem.u
    normal, tangential = impulse_of(problem, delassus(problem), delta_u)
    explained = np.linalg.solve(problem.mass_matrix, problem.wn * normal + problem.wt * tangential)
    residual = departure(problem.mass_matrix, delta_u, explained, problem.u,
                         free_bodies=free_bodies)
    return normal, tangential, residual


def impulse_series(problem, speeds: Sequence) -> list[tuple[float, float]]:
    """``(I_n, I_t)`` of :func:`impulses_from_velocities` for each of ``speeds`` (a run's
    speeds step by step), bit for bit, without the residual nobody reads there."""
    contact_space = delassus(problem)
    return [impulse_of(problem, contact_space, np.asarray(u, dtype=float) - problem.u)
            for u in speeds]


def impulse_of(problem, contact_space: tuple[float, float, float],
                delta_u: np.ndarray) -> tuple[float, float]:
    """The impulse ``(I_n, I_t)`` of (A22)/(A23) behind the change of speeds ``delta_u``,
    with ``contact_space`` the problem's :func:`delassus`."""
    mnn, mnt, mtt = contact_space
    dvn, dvt = float(problem.wn @ delta_u), float(problem.wt @ delta_u)
    det = mnn * mtt - mnt * mnt
    return (mtt * dvn - mnt * dvt) / det, (mnn * dvt - mnt * dvn) / det


def classify_end_state(vt_approach: float, vt_separation: float, vn_approach: float,
                       tolerance: float = STICK_TOLERANCE) -> int | None:
    """Newton numbering from the end state: 1 stick, 2 reverse sliding, 3 forward sliding.

    Sticking means ``|v_t^S| ≤ tolerance·max(|v_n^A|, |v_t^A|)``. Without initial slip
    (``v_t^A`` below the same tolerance) any final slip counts as forward, the solver's
    convention for direct impact.
    """
    if vt_separation is None or not math.isfinite(vt_separation):
        return None
    scale = tolerance * max(abs(vn_approach), abs(vt_approach))
    if abs(vt_separation) <= scale:
        return 1
    if abs(vt_approach) <= scale:
        return 3
    return 3 if (vt_separation > 0) == (vt_approach > 0) else 2


def departure_split(engine_departure: Mapping[str, float],
                    lcp_departure: Mapping[str, float]) -> dict[str, float]:
    """The split of an engine's departure from Poisson (module docstring).

    ``engine_departure`` is the engine record's ``departure``; ``lcp_departure`` the
    ``newton-lcp`` law record's (its entry for ``poisson`` is the law part).
    """
    nan = math.nan
    return {
        "total": _finite(engine_departure.get("poisson", nan)),
        "law_part": _finite(lcp_departure.get("poisson", nan)),
        "solve_part": _finite(engine_departure.get("newton-lcp", nan)),
    }


def _finite(value) -> float:
    return math.nan if value is None else float(value)


__all__ = ["RowScales", "STICK_TOLERANCE", "classify_end_state", "contact_velocities", "delassus",
           "departure", "departure_batch", "departure_split", "departures", "energy_change",
           "frame_free_scale", "impulse_of", "impulse_series", "impulses_from_velocities",
           "ke_norm"]
