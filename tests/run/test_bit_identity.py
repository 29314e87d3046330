"""Every engine run of the library gives the same bits as before the layout/contract refactor.

The stored file holds, per (scenario, point, engine, preset), the post-impact velocities as
``float.hex`` strings recorded at commit 7a12dc3. Engines are deterministic for identical
inputs, so a refactor of the harness around them must not change a single bit; a change to a
scenario or an engine setting must regenerate the file on purpose.
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

STORED = Path(__file__).parent.parent / "data" / "engine-velocities-7a12dc3.json"


@pytest.mark.slow
def test_library_engine_runs_are_bit_identical_to_stored(tmp_path):
    results = tmp_path / "results.json"
    subprocess.run(
        [sys.executable, "-m", "harness.cli", "run", "--no-cache", "--engines",
         "pymunk,pybullet,mujoco", "--json", str(results)],
        check=True, capture_output=True, text=True,
    )
    records = json.loads(results.read_text())["records"]
    current = {
        (r["scenario"], r["point"]["index"], r["source"], r["preset"]):
            [float(x).hex() for x in r["u_after"]] if r["u_after"] else None
        for r in records if r["source"] in ("pymunk", "pybullet", "mujoco")
    }
    stored = {
        (r["scenario"], r["point"], r["engine"], r["preset"]): r["u_after"]
        for r in json.loads(STORED.read_text())["runs"]
    }
    # Scenarios added to the library since (the tilted sweeps) add runs; every stored run
    # must still be there with the same bits.
    assert set(stored) <= set(current), "stored engine runs are missing"
    changed = sorted(key for key in stored if current[key] != stored[key])
    assert not changed, f"{len(changed)} runs changed bits, first: {changed[:5]}"
