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
	$(BIN)/python -m pytest -q -n 2 --dist loadscope
# the kernel_sensitive tests again on other kernels: OPENBLAS_CORETYPE=Prescott and
# NPY_DISABLE_CPU_FEATURES (every numpy SIMD target off); see tests/other_kernels.py
	$(BIN)/python tests/other_kernels.py -n 2 --dist loadscope

bench: $(STAMP)
	$(BIN)/impact-harness bench --quick

stress: $(STAMP)
	$(BIN)/impact-harness stress --quick

clean:
	rm -rf $(VENV) .pytest_cache .hypothesis .cache
