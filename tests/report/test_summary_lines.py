"""summary.md's list of the runs not ok: one readable line per run."""

from __future__ import annotations

from harness.report.summary import run_not_ok_line
from harness.run.records import Record


def _run(label: str, status: str, reasons: list[str]) -> Record:
    return Record(scenario="disk-strikes-rod", point={"index": 0, "label": label},
                  source="mujoco", preset="defaults", u_after=[0.0, 0.0, 0.0], status=status,
                  reasons=[{"name": name, "value": 1.0, "tolerance": 0.5} for name in reasons])


def test_a_status_is_not_repeated_as_its_reason_and_an_empty_point_leaves_no_gap():
    line = run_not_ok_line(_run("", "penetration", ["penetration"]))
    assert line == "disk-strikes-rod mujoco.defaults: penetration"


def test_reasons_beyond_the_status_are_listed():
    line = run_not_ok_line(_run("angle=90", "flagged", ["multi-contact", "penetration"]))
    assert line.endswith(": flagged (multi-contact, penetration)")
    assert line.startswith("disk-strikes-rod angle=90 ")


def test_the_counts_per_reason_say_what_each_reason_means():
    from harness.report.summary import escape, runs_lines
    from harness.run.records import Results
    from harness.run.verdicts import REASONS

    runs = [_run("", "no-separation", ["no-separation"]), _run("", "flagged", ["not-separated"])]
    lines = runs_lines(Results(runs))
    for name in ("no-separation", "not-separated"):
        (line,) = [text for text in lines if text.startswith(f"- {name}: 1")]
        assert line.endswith(f" ({escape(REASONS[name])})")
