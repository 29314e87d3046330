"""tests/other_kernels.py picks the OpenBLAS core types a CPU can run from its flags, runs
every pass even after a failure, and reports each kernel with its outcome."""

from __future__ import annotations

import os
import platform
import sys
from pathlib import Path

import pytest

from tests import other_kernels

TESTS = Path(other_kernels.__file__).resolve().parent
ROOT = TESTS.parent

HASWELL_CPU = "processor\t: 0\nflags\t\t: fpu sse2 pni ssse3 sse4_1 sse4_2 popcnt avx avx2 fma\n"
AVX512_CPU = HASWELL_CPU.replace("fma", "fma avx512f avx512cd avx512bw avx512dq avx512vl")


def test_core_types_follow_the_cpus_flags():
    assert other_kernels.cpu_flags("no flags here") == set()
    assert other_kernels.runnable_core_types(other_kernels.cpu_flags(HASWELL_CPU)) == [
        "Prescott", "Nehalem", "SandyBridge", "Haswell", "Zen"]
    avx512 = other_kernels.runnable_core_types(other_kernels.cpu_flags(AVX512_CPU))
    assert avx512[-1] == "SkylakeX"  # Cooperlake needs avx512_bf16 too
    assert other_kernels.runnable_core_types(
        other_kernels.cpu_flags(AVX512_CPU.replace("avx512vl", "avx512vl avx512_bf16"))
    )[-2:] == ["SkylakeX", "Cooperlake"]
    assert other_kernels.runnable_core_types({"sse2"}) == []


@pytest.mark.skipif(platform.machine().lower() not in ("x86_64", "amd64"), reason="x86-64 only")
def test_prescott_runs_everything_with_simd_off_the_others_what_blas_can_move():
    planned = other_kernels.passes(other_kernels.cpu_flags(HASWELL_CPU))
    assert planned[0] == ("Prescott", True, "kernel_sensitive")
    assert [name for name, _, _ in planned[1:]] == ["Nehalem", "SandyBridge", "Haswell", "Zen"]
    assert {(simd_off, tests) for _, simd_off, tests in planned[1:]} == {
        (False, "kernel_sensitive and not blas_free")}
    environment, changes = other_kernels.kernel_environment("Haswell", simd_off=False)
    assert environment["OPENBLAS_CORETYPE"] == "Haswell"
    assert "NPY_DISABLE_CPU_FEATURES" not in environment
    assert changes == ["OPENBLAS_CORETYPE=Haswell"]


def test_every_pass_runs_and_the_report_names_each_kernel(monkeypatch, capsys):
    flags = other_kernels.cpu_flags(AVX512_CPU)
    monkeypatch.setattr(other_kernels, "cpu_flags", lambda: flags)
    monkeypatch.setattr(platform, "machine", lambda: "x86_64")
    calls = []

    def run_passes(runs, at_once, cwd):
        calls.extend((environment["OPENBLAS_CORETYPE"], command, at_once)
                     for _, command, environment in runs)
        return [(1 if environment["OPENBLAS_CORETYPE"] == "Nehalem" else 0, 1.0, 1.0)
                for _, _, environment in runs]

    monkeypatch.setattr(other_kernels, "run_passes", run_passes)
    assert other_kernels.main(["-q", "--passes-at-once", "2"]) == 1  # the failure's status
    assert [core_type for core_type, _, _ in calls] == [
        "Prescott", "Nehalem", "SandyBridge", "Haswell", "Zen", "SkylakeX"]
    files = [str(path.relative_to(ROOT)) for path in other_kernels.kernel_sensitive_files(TESTS)]
    for _, command, at_once in calls:  # pytest gets the marked files, not --passes-at-once
        assert command[-len(files):] == files and at_once == 2
        assert "--passes-at-once" not in command and "2" not in command
    report = capsys.readouterr().out.split("kernel_sensitive tests on other kernels")[-1]
    assert "FAILED (pytest exit status 1)" in report and "OPENBLAS_CORETYPE=Nehalem" in report
    assert report.count("passed") == 5 and "OPENBLAS_CORETYPE=SkylakeX" in report


def test_passes_at_once_is_read_and_the_rest_goes_to_pytest():
    assert other_kernels.passes_at_once(["-x"]) == (1, ["-x"])
    assert other_kernels.passes_at_once(["--passes-at-once", "3", "-x"]) == (3, ["-x"])
    assert other_kernels.passes_at_once(["-x", "--passes-at-once=2"]) == (2, ["-x"])
    for wrong in (["--passes-at-once", "0"], ["--passes-at-once"], ["--passes-at-once=two"]):
        with pytest.raises(SystemExit, match="count >= 1"):
            other_kernels.passes_at_once(wrong)


def test_passes_run_together_each_output_whole_with_its_own_status_and_cpu(tmp_path, capfd):
    """Two runs at once: the first waits for a file only the second writes (so they overlap),
    burns some CPU, and fails; each one's lines come out together under its title, and its
    status, wall and CPU time are its own."""
    signal = tmp_path / "second-started"
    first = ("import pathlib, sys, time\n"
             "print('first: 1', flush=True)\n"
             f"signal = pathlib.Path({str(signal)!r})\n"
             "deadline = time.monotonic() + 60\n"
             "while not signal.exists() and time.monotonic() < deadline: time.sleep(0.01)\n"
             "burn = time.process_time() + 0.3\n"
             "while time.process_time() < burn: pass\n"
             "print('first: 2')\n"
             "sys.exit(3 if signal.exists() else 4)\n")
    second = ("import pathlib\n"
              "print('second: 1', flush=True)\n"
              f"pathlib.Path({str(signal)!r}).touch()\n"
              "print('second: 2')\n")
    runs = [(title, [sys.executable, "-c", code], dict(os.environ))
            for title, code in (("the first", first), ("the second", second))]
    outcomes = other_kernels.run_passes(runs, at_once=2, cwd=tmp_path)
    assert [status for status, _, _ in outcomes] == [3, 0]  # 3: the two ran at once
    assert outcomes[0][2] >= 0.25 > outcomes[1][2]  # each its own CPU time
    lines = capfd.readouterr().out.split("\n")
    for name in ("first", "second"):
        at = lines.index(f"== the {name}")
        assert lines[at + 1:at + 3] == [f"{name}: 1", f"{name}: 2"]
    assert other_kernels.run_passes(runs[1:], at_once=1, cwd=tmp_path)[0][0] == 0


def test_the_file_rule_finds_a_mark_however_it_is_written(tmp_path):
    (tmp_path / "sub").mkdir()
    files = {
        "test_decorated.py": "import pytest\n@pytest.mark.kernel_sensitive\ndef test_a(): pass\n",
        "sub/test_module.py": "import pytest\npytestmark = pytest.mark.kernel_sensitive\n",
        "sub/params_test.py": "marks=[pytest.mark.kernel_sensitive]\n",
        "test_plain.py": "def test_b(): pass\n",
        "helper.py": "# kernel_sensitive, but pytest collects no test here\n",
    }
    for name, text in files.items():
        (tmp_path / name).write_text(text)
    assert other_kernels.kernel_sensitive_files(tmp_path) == [
        tmp_path / "sub/params_test.py", tmp_path / "sub/test_module.py",
        tmp_path / "test_decorated.py"]


def test_every_kernel_sensitive_test_is_in_a_file_the_rule_names(request):
    """The passes of tests/other_kernels.py collect only the files its rule names: each test
    this session collected with the kernel_sensitive mark (as the whole suite's collection
    marks it, conftest hooks and module marks included) must sit in one of them. The check is
    over this session's items, so it needs the whole suite collected (as make test does)."""
    config = request.config
    arguments = {(config.invocation_params.dir / argument.partition("::")[0]).resolve()
                 for argument in config.args}
    if not arguments <= {TESTS, ROOT} or config.option.keyword or config.option.markexpr:
        pytest.skip("this session did not collect the whole suite")
    marked = {item.path for item in request.session.items
              if item.get_closest_marker("kernel_sensitive")}
    if not marked:
        pytest.skip("this session collected no kernel_sensitive test")
    missed = marked - set(other_kernels.kernel_sensitive_files(TESTS))
    assert not missed, f"kernel_sensitive tests in files the rule misses: {sorted(missed)}"


def test_skip_native_leaves_out_only_the_pass_the_whole_suite_just_ran(monkeypatch):
    """make test's --skip-native: the native core type's pass with numpy's SIMD as it is
    goes (the whole suite ran every kernel_sensitive test so), never Prescott's SIMD-off
    pass, nor anything when the native kernel is unknown or not among the passes."""
    planned = other_kernels.passes(other_kernels.cpu_flags(AVX512_CPU))
    kept, skipped = other_kernels.without_native(planned, "Haswell")
    assert skipped == "Haswell" and len(kept) == len(planned) - 1
    assert [entry for entry in planned if entry not in kept] == [
        ("Haswell", False, "kernel_sensitive and not blas_free")]
    # Prescott's pass turns numpy's SIMD off: not what the suite ran, so it stays
    assert other_kernels.without_native(planned, "Prescott") == (planned, None)
    assert other_kernels.without_native(planned, None) == (planned, None)
    assert other_kernels.without_native(planned, "Sapphire") == (planned, None)
    monkeypatch.setenv("OPENBLAS_CORETYPE", "SkylakeX")
    assert other_kernels.native_core_type() == "SkylakeX"
