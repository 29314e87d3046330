"""Every engine run of the library gives the velocities it gave before the layout/contract
refactor, to a stated bound.

The stored file holds, per (scenario, point, engine, preset), the post-impact velocities as
``float.hex`` strings recorded at commit 7a12dc3. Engines are deterministic for identical
inputs, and on the machine that recorded them the runs still give the same bits. But the
scenes handed to the engines are built with numpy (poses, contact geometry: BLAS products)
and the engines are compiled C with their own float code over libm, so another CPU feeds
them inputs a last bit apart, which a thousand steps carry on: relative 1e-13 of the
velocities seen under OpenBLAS's Prescott kernel. A run departs when a velocity moves more
than :data:`RELATIVE` of the run's largest speed (before or after); a change to a scenario
or an engine setting, which moves them by far more, must regenerate the file on purpose.

Kind of comparison (docs/verdicts.md, 'Same answers on every CPU'): a decision with a
tolerance band ("is this the stored run?"), not a derived bound: the error of a thousand
engine steps has no forward bound, so the band is set between the measured drift of the last
bits and the smallest change the pin must catch, four orders of magnitude either side.
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

STORED = Path(__file__).parent.parent / "data" / "engine-velocities-7a12dc3.json"
#: How far an engine's velocity may move, relative to the run's largest speed: a band, not a
#: derived bound (docstring).
RELATIVE = 1e-9


def departs(now: list[float] | None, then: list[str] | None, u_before: list[float]) -> bool:
    """Whether velocities ``now`` depart from the stored ``then`` (``float.hex``): one of
    them missing, or a velocity more than :data:`RELATIVE` of the run's largest speed."""
    if now is None or then is None:
        return (now is None) != (then is None)
    stored = [float.fromhex(value) for value in then]
    scale = max(map(abs, [*u_before, *now, *stored]))
    return len(now) != len(stored) or any(abs(a - b) > RELATIVE * scale
                                          for a, b in zip(now, stored))


@pytest.mark.slow
@pytest.mark.kernel_sensitive
def test_library_engine_runs_are_those_stored_within_the_bound(tmp_path):
    results = tmp_path / "results.json"
    subprocess.run(
        [sys.executable, "-m", "harness.cli", "run", "--no-cache", "--engines",
         "pymunk,pybullet,mujoco", "--json", str(results)],
        check=True, capture_output=True, text=True,
    )
    records = json.loads(results.read_text())["records"]
    current = {(r["scenario"], r["point"]["index"], r["source"], r["preset"]): r
               for r in records if r["source"] in ("pymunk", "pybullet", "mujoco")}
    stored = {
        (r["scenario"], r["point"], r["engine"], r["preset"]): r["u_after"]
        for r in json.loads(STORED.read_text())["runs"]
    }
    # Scenarios added to the library since (the tilted sweeps) add runs; every stored run
    # must still be there with the same velocities.
    assert set(stored) <= set(current), "stored engine runs are missing"
    changed = sorted(key for key in stored
                     if departs(current[key]["u_after"] or None, stored[key],
                                current[key]["u_before"]))
    assert not changed, f"{len(changed)} runs changed velocities, first: {changed[:5]}"


def test_the_bound_takes_the_last_bits_and_catches_a_change():
    then = [(0.5).hex(), (-1.25).hex(), (0.0).hex()]
    assert not departs([0.5, -1.25, 0.0], then, [1.0, 2.0, 0.0])
    assert not departs([0.5 * (1 + 1e-13), -1.25, 1e-13], then, [1.0, 2.0, 0.0])
    assert departs([0.5 * (1 + 1e-6), -1.25, 0.0], then, [1.0, 2.0, 0.0])
    assert departs([0.5, -1.25, 0.0], None, [1.0, 2.0, 0.0])
    assert departs(None, then, [1.0, 2.0, 0.0])
