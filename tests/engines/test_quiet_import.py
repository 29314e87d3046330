"""Engines import without their C code's output (harness/engines/quiet.py): pybullet writes
its build time to the process's file descriptors on import."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]


def _run(code: str) -> subprocess.CompletedProcess:
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(ROOT / "src"), str(ROOT)]))
    return subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          env=env, cwd=ROOT, timeout=120)


@pytest.mark.parametrize("load", [
    "from harness.engines import load_engine; load_engine('pybullet')",
    "import harness.engines.pybullet",
])
def test_pybullet_loads_without_its_banner(load):
    pytest.importorskip("pybullet")
    done = _run(f"import sys; print('out before'); print('err before', file=sys.stderr)\n"
                f"{load}\nprint('out after'); print('err after', file=sys.stderr)")
    assert done.returncode == 0, done.stderr
    assert "build time" not in done.stdout + done.stderr
    assert done.stdout.split() == ["out", "before", "out", "after"]
    assert done.stderr.split() == ["err", "before", "err", "after"]


def test_output_is_dropped_inside_only_and_errors_still_raise():
    done = _run("import os, sys\nfrom harness.engines.quiet import c_output_dropped\n"
                "with c_output_dropped():\n"
                "    os.write(1, b'hidden out\\n'); os.write(2, b'hidden err\\n')\n"
                "os.write(1, b'shown out\\n'); os.write(2, b'shown err\\n')\n"
                "try:\n"
                "    with c_output_dropped():\n"
                "        raise KeyError('raised')\n"
                "except KeyError:\n"
                "    print('caught')\n")
    assert done.returncode == 0, done.stderr
    assert done.stdout == "shown out\ncaught\n" and done.stderr == "shown err\n"
