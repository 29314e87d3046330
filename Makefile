# Two commands set everything up on a fresh machine with Python 3.11:
#   make validate   create .venv if missing, install, run the validation suite, write reports/
#   make test       create .venv if missing, run the whole test suite, then its
#                   numerically sensitive tests again on other kernels (tests/other_kernels.py)
PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed

.PHONY: validate test venv clean bench stress

$(STAMP): pyproject.toml
	test -d $(VENV) || $(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e ".[harness,test]"
# Drake (pyproject's `drake` extra, pinned there) in a second step allowed to fail: its
# wheels need glibc >= 2.34 on x86_64/aarch64 Linux, or macOS. Without it every output says
# Drake is not installed and why (harness/engines/__init__.py, EngineNotInstalled).
	$(BIN)/python -m pip install --quiet "$$($(BIN)/python -c 'from harness.engines import pinned_requirement; print(pinned_requirement("drake"))')" \
	  || echo "make: Drake not installed (no wheel for this platform?); the other engines run without it"
	touch $(STAMP)

venv: $(STAMP)

validate: $(STAMP)
	$(BIN)/impact-harness suite

test: $(STAMP)
	$(BIN)/ruff check .
# --dist loadscope: a module's tests share one worker, so a module-scoped fixture (a
# library run, a report) is built once, not once per worker
# then the kernel_sensitive tests again on other kernels (tests/other_kernels.py): the whole
# set under OPENBLAS_CORETYPE=Prescott with NPY_DISABLE_CPU_FEATURES (every numpy SIMD target
# off), and under every other OpenBLAS core type this CPU can run (Nehalem, SandyBridge,
# Haswell, Zen; SkylakeX and Cooperlake with AVX-512), read from /proc/cpuinfo. Each pass is
# one pytest process over only the files that name kernel_sensitive, two passes at a time
# (tests/other_kernels.py's docstring says why that is quicker than xdist workers), but the
# pass of this run's own kernel with numpy's SIMD as it is (--skip-native: the whole suite
# has just run every kernel_sensitive test exactly so). Both steps
# run even when the first fails; the last line reports both, and make fails if either did.
# Both steps write Python's bytecode caches even where PYTHONDONTWRITEBYTECODE is set (empty
# is unset for Python): without them every pytest process compiles each test module it
# collects again, its asserts rewritten: 5 s of CPU per xdist worker for the whole suite,
# 1 s per kernel pass (measured; __pycache__/ is git-ignored).
	@export PYTHONDONTWRITEBYTECODE=; suite=0; kernels=0; \
	echo "$(BIN)/python -m pytest -q -n 2 --dist loadscope"; \
	$(BIN)/python -m pytest -q -n 2 --dist loadscope || suite=$$?; \
	echo "$(BIN)/python tests/other_kernels.py --passes-at-once 2 --skip-native"; \
	$(BIN)/python tests/other_kernels.py --passes-at-once 2 --skip-native || kernels=$$?; \
	if [ $$suite = 0 ]; then s=passed; else s="FAILED (pytest exit status $$suite)"; fi; \
	if [ $$kernels = 0 ]; then k=passed; else k="FAILED (exit status $$kernels)"; fi; \
	echo "make test: whole suite $$s; kernel_sensitive tests on other kernels $$k"; \
	[ $$suite = 0 ] && [ $$kernels = 0 ]

bench: $(STAMP)
	$(BIN)/impact-harness bench --quick

stress: $(STAMP)
	$(BIN)/impact-harness stress --quick

clean:
	rm -rf $(VENV) .pytest_cache .hypothesis .cache
