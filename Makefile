# DroneWrapper on Zenoh. `make demo` flies the simulated follow mission; `make test` runs the suite.
PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed
# every distribution of the repository: the contract, the runtime, the SDK client and its tools,
# one per service, the simulator and the graphs
DISTS  := contract runtime sdk tools $(patsubst %/pyproject.toml,%,$(wildcard services/*/pyproject.toml)) sim compose
# the tests start hundreds of Python processes: their imports read bytecode compiled once here,
# not each process's own compile of every module (none is written where PYTHONDONTWRITEBYTECODE
# is set); compileall only rewrites what changed
BYTECODE := $(BIN)/python -m compileall -q -j 0 -x '/(\.venv|build|\.[a-z_]+_cache)/' $(DISTS) tests

.PHONY: setup onboard demo test test-unit test-fast bench lint typecheck format clean

setup: $(STAMP)

$(STAMP): pyproject.toml $(DISTS:%=%/pyproject.toml)
	@test -x $(BIN)/python || $(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install -q --upgrade pip
	$(BIN)/python -m pip install -q $(DISTS:%=-e ./%) '.[dev]'  # the root holds no code: not editable
	$(BIN)/python -m pip install -q --no-deps 'djitellopy==2.5.0'  # test client; its opencv-python would shadow our headless cv2
	@touch $(STAMP)

onboard:  # a companion computer (a Jetson): the stack without the test tools (docs/jetson.md)
	@test -x $(BIN)/python || $(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install -q --upgrade pip
	$(BIN)/python -m pip install -q $(DISTS:%=-e ./%) .  # the root holds no code: not editable

demo: setup
	$(BIN)/python -m dronewrapper_compose.demo $(ARGS)

test: setup lint typecheck
	@$(BYTECODE) >/dev/null
	$(BIN)/python -m pytest -q $(ARGS)

test-unit: setup
	$(BIN)/python -m pytest -q tests/unit $(ARGS)

# the unit and service tiers: no sockets, no processes, injected time. Their tests share nothing,
# so they run on every core (-n auto: one worker per core, each collecting the tiers). The code
# under test is compiled first, once, on every core (in a fresh tree each worker compiled all of
# it itself). The assertion rewriting of the tiers' ~210 test modules (6 s of CPU per worker in a
# fresh tree) is kept in __pycache__ for the next run even where PYTHONDONTWRITEBYTECODE is set;
# neither tier uses hypothesis' or anyio's plugin.
test-fast: setup
	@$(BYTECODE) >/dev/null
	PYTHONDONTWRITEBYTECODE= $(BIN)/python -m pytest -q -n auto -p no:hypothesispytest -p no:anyio \
	  tests/unit tests/service $(ARGS)

bench: setup
	$(BIN)/python -m bench $(ARGS)

lint: setup  # ruff; vermin: the on-board code runs on a Jetson's Python 3.10
	$(BIN)/ruff check .
	$(BIN)/ruff format --check .
	$(BIN)/vermin -t=3.10- --no-tips --violations --eval-annotations -q \
	  contract/dronewrapper runtime/dronewrapper sdk/dronewrapper tools/dronewrapper $(filter-out %.egg-info,$(wildcard services/*/dronewrapper_*)) sim/dronewrapper_sim compose/dronewrapper_compose

typecheck: setup  # mypy over every package (the files and settings: pyproject.toml)
	$(BIN)/mypy

format: setup
	$(BIN)/ruff check --fix .
	$(BIN)/ruff format .

clean:
	rm -rf $(VENV) build .pytest_cache .ruff_cache .mypy_cache bench/results/*.json
