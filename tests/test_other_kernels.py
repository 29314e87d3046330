"""tests/other_kernels.py picks the OpenBLAS core types a CPU can run from its flags, runs
every pass even after a failure, and reports each kernel with its outcome."""

from __future__ import annotations

import platform

import pytest

from tests import other_kernels

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

    def call(command, cwd, env):
        calls.append(env["OPENBLAS_CORETYPE"])
        return 1 if env["OPENBLAS_CORETYPE"] == "Nehalem" else 0

    monkeypatch.setattr(other_kernels.subprocess, "call", call)
    assert other_kernels.main(["-q"]) == 1  # the failure's status, after every pass
    assert calls == ["Prescott", "Nehalem", "SandyBridge", "Haswell", "Zen", "SkylakeX"]
    report = capsys.readouterr().out.split("kernel_sensitive tests on other kernels")[-1]
    assert "FAILED (pytest exit status 1)" in report and "OPENBLAS_CORETYPE=Nehalem" in report
    assert report.count("passed") == 5 and "OPENBLAS_CORETYPE=SkylakeX" in report
