"""A scenario's ``[expect.gate]`` tables checked against its engine records: a gate fails
when a run that is a single impact departs from the law by more than the gate allows; a
skipped or flagged run, or a law that does not apply to the point, is not checked (said
why)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Sequence

from harness.run import references, verdicts
from harness.run.metrics import fmt_departure
from harness.run.records import Record
from harness.scenarios import Scenario


@dataclass
class GateResult:
    """One ``[expect.gate]`` checked against one engine record."""

    scenario: str
    gate: str  # "pymunk.accurate" or "pymunk"
    law: str
    max_departure: float
    point: str
    record: str  # engine.preset
    departure: float | None
    status: str  # "pass", "FAIL" or "not checked: <why>"

    @property
    def failed(self) -> bool:
        return self.status == "FAIL"

    def describe(self) -> str:
        where = f" at {self.point}" if self.point else ""
        # In percent, as the report shows departures; the gate's limit also as the scenario
        # file writes it (a fraction), so that the two can be matched.
        value, limit = fmt_departure(self.departure), fmt_departure(self.max_departure)
        if value == limit and self.departure is not None:  # apart only beyond 3 digits
            value, limit = (f"{100.0 * self.departure:.6g}%",
                            f"{100.0 * self.max_departure:.6g}%")
        return (f"scenario {self.scenario!r} [expect.gate] \"{self.gate}\" ({self.record}{where}): "
                f"departure from {self.law} {value} vs max {limit} (max_departure = "
                f"{self.max_departure:g}): {self.status}")


def check_gates(scenario: Scenario, records: Sequence[Record]) -> list[GateResult]:
    """Every ``[expect.gate]`` of ``scenario`` against its engine records."""
    results = []
    for gate in scenario.expect.gates:
        matching = [r for r in records if r.source == gate.engine
                    and (gate.preset is None or r.preset == gate.preset)]
        if not matching:
            results.append(GateResult(scenario.name, gate.source, gate.law, gate.max_departure,
                                      "", gate.source, None,
                                      "not checked: engine or preset not run"))
            continue
        for record in matching:
            value = record.departure.get(gate.law)
            situation = ((record.diagnostics or {}).get("reference") or {}).get(
                "kind", references.SINGLE)
            if record.skipped:
                status = f"not checked: {record.status}"
            elif record.verdict == verdicts.FLAGGED:  # not a single impact: no departure
                status = f"not checked: flagged ({', '.join(record.failing_reasons)})"
            elif situation != references.SINGLE and value is None:  # a law that does not apply
                status = (f"not checked: {gate.law} does not apply to a {situation} point "
                          "(its references: docs/multi-contact.md)")
            elif value is None or not math.isfinite(value):
                status = "FAIL"
            else:
                status = "pass" if value <= gate.max_departure else "FAIL"
            results.append(GateResult(scenario.name, gate.source, gate.law, gate.max_departure,
                                      record.point["label"], record.label,
                                      None if value is None or not math.isfinite(value)
                                      else float(value), status))
    return results


__all__ = ["GateResult", "check_gates"]
