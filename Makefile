# posegen: every target installs what it needs into .venv first.
PYTHON ?= python3
VENV := .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.installed-stamp
export OPENBLAS_NUM_THREADS := 1
export OMP_NUM_THREADS := 1
export MKL_NUM_THREADS := 1
DEMO := plans/demo

.PHONY: install demo test slow lint bench clean browser lock kill-matrix fuzz docs

LOCK := constraints.txt

# Every package at the version in $(LOCK) (the versions `make test` was last run with),
# the build backend included (no build isolation): a new release upstream changes nothing.
$(STAMP): pyproject.toml $(LOCK)
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet -c $(LOCK) --upgrade pip setuptools
	$(PY) -m pip install --quiet -c $(LOCK) --no-build-isolation -e '.[all,dev,docs]'
	touch $(STAMP)

install: $(STAMP)

demo: $(STAMP)
	$(VENV)/bin/posegen pool --n 300 --seed 1 -o $(DEMO)/pool.yaml
	$(VENV)/bin/posegen check $(DEMO)/pool.yaml
	$(VENV)/bin/posegen select $(DEMO)/pool.yaml --k 60 --runs 2 -o $(DEMO)/selected.yaml
	$(VENV)/bin/posegen route $(DEMO)/selected.yaml -o $(DEMO)/route.yaml
	$(VENV)/bin/posegen check $(DEMO)/route.yaml
	$(VENV)/bin/posegen export $(DEMO)/route.yaml --bag $(DEMO)/route_bag
	$(VENV)/bin/posegen simulate $(DEMO)/route.yaml --bag $(DEMO)/session --seed 7 --compliance 0.3
	$(VENV)/bin/posegen measure $(DEMO)/session --route $(DEMO)/route.yaml --session sim -o $(DEMO)/measured.yaml
	$(VENV)/bin/posegen simulate plans/talos/pool.yaml --seed 7 --compliance 0.3 -o $(DEMO)/sim_heldout.yaml
	$(VENV)/bin/posegen calibrate $(DEMO)/measured.yaml --validate $(DEMO)/sim_heldout.yaml \
		--candidates full full_hip_pitch offsets_hip_pitch offsets_legs_hip_pitch -o $(DEMO)/calibration
	$(VENV)/bin/posegen select $(DEMO)/pool.yaml --given $(DEMO)/measured.yaml \
		--calibration $(DEMO)/calibration/calibration.yaml --k 10 -o $(DEMO)/next.yaml
	$(VENV)/bin/posegen view $(DEMO)/selected.yaml --html $(DEMO)/selected.html
	$(VENV)/bin/posegen view $(DEMO)/route.yaml --html $(DEMO)/route.html

lint: $(STAMP)
	$(VENV)/bin/ruff check posegen tests benchmarks examples docs setup.py
	$(VENV)/bin/mypy posegen

# Headless Chromium for the viewer's browser tests and benchmark: Debian's package, installed
# with apt-get when missing and we are root; otherwise those tests are skipped (and say why).
browser:
	@command -v chromium-headless-shell >/dev/null 2>&1 || command -v chromium >/dev/null 2>&1 || \
	if [ "$$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then \
		echo "installing chromium-headless-shell (apt-get) for the browser tests"; \
		{ apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq chromium-headless-shell >/dev/null; } \
		|| echo "posegen: could not install chromium-headless-shell: the browser tests will be skipped"; \
	else \
		echo "posegen: no headless Chromium and no root apt-get: the browser tests will be skipped"; \
	fi

# The suite on TEST_WORKERS processes (pytest-xdist; 2 cores here; an idle process takes tests from a
# busy one's queue): each builds the shared fixtures it needs once. TEST_WORKERS=0: one process.
TEST_WORKERS ?= 2
test: lint browser
	$(PY) -m pytest -q -n $(TEST_WORKERS) --dist worksteal -m 'not slow' tests

# The slow checks (a step of .ci/run): the kill matrix at every crash point, every shipped robot
# end to end, the whole example pipeline, the pipeline's byte manifest, the session tests on a
# started or rehearsed session, a simulated session through rosbag2, kills of `session add`.
slow: $(STAMP)
	POSEGEN_KILL_MATRIX=full $(PY) -m pytest -q -m slow tests

# Every command killed at every crash point, the files a folder is staged from included (~10 min).
kill-matrix: $(STAMP)
	POSEGEN_KILL_MATRIX=full $(PY) -m pytest -q tests/robustness/test_kill_matrix.py

# The fuzz suite with new random draws and many examples (~10 min; make test runs a few, fixed):
# the old surfaces, robot init, the session index, the deliverables, bags over folders, kills of session add.
FUZZ_TESTS := tests/robustness/test_fuzz.py tests/robustness/test_readers.py \
	tests/robustness/test_fuzz_surfaces.py tests/session/test_journal.py
fuzz: $(STAMP)
	HYPOTHESIS_PROFILE=fuzz $(PY) -m pytest -q $(FUZZ_TESTS)

# The documentation site (Sphinx: docs/*.md and the API from the docstrings); warnings are errors.
docs: $(STAMP)
	$(PY) -m sphinx -b html -W --keep-going -q docs docs/_build/html
	@echo "docs: docs/_build/html/index.html"

bench: $(STAMP) browser
	$(PY) benchmarks/run.py

# Rewrite the lock from a fresh venv: the locked versions kept and new dependencies at the
# newest versions allowed, or with UPGRADE=1 everything at the newest versions allowed.
# Then run `make test` (it reinstalls from the new lock) and commit $(LOCK) if it passes.
lock:
	rm -rf .venv-lock
	$(PYTHON) -m venv .venv-lock
	.venv-lock/bin/python -m pip install --quiet $(if $(UPGRADE),,-c $(LOCK)) --upgrade pip setuptools
	.venv-lock/bin/python -m pip install --quiet $(if $(UPGRADE),,-c $(LOCK)) --no-build-isolation -e '.[all,dev,docs]'
	echo "# The versions make test runs with (pip constraints); make lock refreshes them (README)." > $(LOCK).new
	.venv-lock/bin/python -m pip freeze --all --exclude-editable >> $(LOCK).new
	mv $(LOCK).new $(LOCK)
	rm -rf .venv-lock

clean:
	rm -rf $(VENV) .venv-lock $(DEMO) .pytest_cache .mypy_cache .ruff_cache docs/_build build dist
