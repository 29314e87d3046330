"""``impact-harness report`` says where it is on stderr once it has taken a while, and
nothing before (harness/report/progress.py)."""

from __future__ import annotations

import io
import time

from harness.report.progress import Progress


def test_silent_before_the_delay_then_the_step_and_the_figures_written(tmp_path):
    stream = io.StringIO()
    with Progress(stream, after_s=60.0) as progress:  # a report done within the delay
        progress.step("building the page")
    assert stream.getvalue() == ""
    figures = [tmp_path / "a.png", tmp_path / "b.png"]
    stream = io.StringIO()
    with Progress(stream, after_s=0.05, every_s=0.05) as progress:
        progress.drawing(figures)
        progress.step("drawing the figures")
        figures[0].write_bytes(b"png")
        time.sleep(0.3)
    lines = stream.getvalue().splitlines()
    assert lines and lines[-1].startswith(
        "report: drawing the figures; 1 of 2 figures written (")
    assert lines[-1].endswith(" s)")
