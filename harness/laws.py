"""The impact laws as the harness shows them: one entry per law, read everywhere.

The solvers of each law live in :mod:`planar_impact` (one line of its
``law_table.LAW_TABLE``, whose names are ``pi.LAWS``; ``pi.solve`` and ``pi.solve_batch``
run them); what the harness adds is here and nowhere else: the order
laws are listed in (tables, figures' legends, ``compare``), the report's label, the figures'
style, the collision types a law reports, and what a law promises (docs/theory.md, 'The
laws'). Modules ask :data:`LAW_NAMES`, :func:`law` or :data:`REGISTRY`; no module keeps its
own list of the laws (tests/test_laws.py fails on one).

Adding a law: its solvers' module and one line of ``planar_impact.law_table.LAW_TABLE``,
one :class:`Law` line in :data:`REGISTRY` below (tests/test_laws.py checks the two name the
same laws), and its section in docs/theory.md.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Law:
    """What the harness knows about one law of :data:`planar_impact.LAWS`."""

    name: str  # the solver's name (pi.solve(law=name))
    label: str  # the report's name for it, in tables and legends
    colour: str  # figures: a colour distinct from the engines' Okabe–Ito ones
    line: str  # figures: matplotlib line style
    marker: str  # figures: matplotlib marker (a path's end, a point)
    collision_types: tuple[int, ...]  # the types it reports (docs/theory.md, Table 1)
    #: Never gains kinetic energy (docs/theory.md; the findings count the gains of the others).
    no_energy_gain: bool
    #: Its impulse lies in the friction cone, |I_t| <= μ I_n, and I_n >= 0.
    in_cone: bool
    #: It is a path of the exact impulse process (drawn on Routh's diagram), not a closed form
    #: off it (the paper's Stronge mapping ends off the process; newton-lcp is velocity-level).
    process: bool
    #: A headline law: the report's departures are shown against it first.
    headline: bool = False


#: Every law, in the order the harness lists them. Types: Poisson/Stronge 1–5, the Newton laws
#: 1 stick, 2 reverse sliding, 3 forward sliding.
REGISTRY: tuple[Law, ...] = (
    Law("poisson", "Poisson", "black", "-", "o", (1, 2, 3, 4, 5),
        no_energy_gain=True, in_cone=True, process=True, headline=True),
    Law("stronge", "Stronge (exact)", "tab:red", "-", "^", (1, 2, 3, 4, 5),
        no_energy_gain=True, in_cone=True, process=True, headline=True),
    Law("stronge-paper", "Stronge (paper's mapping)", "tab:purple", "--", "v", (1, 2, 3, 4, 5),
        no_energy_gain=False, in_cone=True, process=False),
    Law("newton", "Newton (process)", "tab:gray", "-.", "s", (1, 2, 3),
        no_energy_gain=False, in_cone=True, process=True),
    Law("newton-lcp", "newton-lcp (engines' law)", "tab:brown", ":", "D", (1, 2, 3),
        no_energy_gain=False, in_cone=True, process=False),
)

_BY_NAME = {entry.name: entry for entry in REGISTRY}
#: The laws' names in the harness's order.
LAW_NAMES: tuple[str, ...] = tuple(entry.name for entry in REGISTRY)
#: The laws the report shows departures against first (Poisson, Stronge).
HEADLINE_LAWS: tuple[str, ...] = tuple(entry.name for entry in REGISTRY if entry.headline)
#: The laws that are paths of the exact impulse process.
PROCESS_LAWS: tuple[str, ...] = tuple(entry.name for entry in REGISTRY if entry.process)

def law(name: str) -> Law:
    """The entry of law ``name``; ``ValueError`` naming the laws for another name."""
    try:
        return _BY_NAME[name]
    except KeyError:
        raise ValueError(f"unknown law {name!r}; allowed: {', '.join(LAW_NAMES)}") from None


#: Rounding band of the cone promise, relative to ``|I_n| + |I_t|``: the closed forms put
#: ``I_t`` at ``±μ I_n`` up to a few roundings (~1e-16); 1e-9 leaves every CPU's last bits in.
CONE_BAND = 1e-9


def broken_promises(name: str, result, mu: float) -> list[str]:
    """What law ``name``'s solution ``result`` (a :class:`planar_impact.ImpactResult`)
    breaks of its entry's promises, one sentence each (checked on every solution the runner
    keeps: a solver fault shows in the results, never silently)."""
    entry = law(name)
    broken = []
    normal, tangential = result.normal_impulse, result.tangential_impulse
    if entry.no_energy_gain and result.energy_gained:  # the bar, beyond (A29)'s rounding band
        broken.append(f"{name} promises no energy gain but gains {result.energy_change:.3g} J")
    band = CONE_BAND * (abs(normal) + abs(tangential))
    if entry.in_cone and (normal < -band or abs(tangential) > mu * normal + band):
        broken.append(f"{name} promises an impulse in the friction cone but gives I_n = "
                      f"{normal:.6g}, I_t = {tangential:.6g} N s at μ = {mu:g}")
    return broken


def law_order(name: str) -> int:
    """The position of ``name`` in :data:`LAW_NAMES` (an unknown name sorts last)."""
    return LAW_NAMES.index(name) if name in _BY_NAME else len(LAW_NAMES)


__all__ = ["CONE_BAND", "HEADLINE_LAWS", "LAW_NAMES", "PROCESS_LAWS", "REGISTRY", "Law",
           "broken_promises", "law", "law_order"]
