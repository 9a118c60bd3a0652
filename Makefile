# The two set-up commands of the README. Both create .venv on first use.
PYTHON ?= python3
VENV := .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.requirements-installed

.PHONY: demo test bench bench-node bench-stream bench-soak bench-depth bench-depth-node clean

$(STAMP): requirements.txt setup.py
	test -x $(PY) || $(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -r requirements.txt
	# The package itself, editable (it runs this checkout): .venv/bin/dgmod and
	# .venv/bin/detector. colcon builds from the same sources into its own prefix.
	$(PY) -m pip install --quiet -e .
	touch $(STAMP)

# numba compiles the kernels once per install (30-60 s on two cores, holding
# the GIL); compiling them here, into the on-disk cache, keeps that out of
# the demo's first start and out of the tests' time-outs (docs/node.md,
# "First start"). A warm cache makes this a two-second load.
KERNELS := $(PY) -m dgmod_ros.core.warmup

demo: $(STAMP)
	$(KERNELS)
	$(PY) -m dgmod_ros.demo $(DEMO_ARGS)

test: $(STAMP)
	$(KERNELS)
	$(PY) -m pytest -q test $(PYTEST_ARGS)

bench: $(STAMP)
	PYTHONPATH=. $(PY) benchmarks/bench_solver.py

bench-node: $(STAMP)
	PYTHONPATH=. $(PY) benchmarks/bench_node.py $(BENCH_ARGS)

bench-stream: $(STAMP)
	PYTHONPATH=. $(PY) benchmarks/bench_stream.py $(BENCH_ARGS)

bench-soak: $(STAMP)
	PYTHONPATH=. $(PY) benchmarks/bench_soak.py

bench-depth: $(STAMP)
	PYTHONPATH=. $(PY) benchmarks/bench_depth.py

bench-depth-node: $(STAMP)
	PYTHONPATH=. $(PY) benchmarks/bench_depth_node.py $(BENCH_ARGS)

clean:
	rm -rf $(VENV) out dgmod_ros.egg-info
