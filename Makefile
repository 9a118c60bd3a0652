# The two set-up commands of the README. Both create .venv on first use.
PYTHON ?= python3
VENV := .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.requirements-installed

.PHONY: demo test bench bench-node bench-stream bench-soak clean

$(STAMP): requirements.txt
	test -x $(PY) || $(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -r requirements.txt
	touch $(STAMP)

demo: $(STAMP)
	$(PY) -m dgmod_ros.demo $(DEMO_ARGS)

test: $(STAMP)
	$(PY) -m pytest -q test $(PYTEST_ARGS)

bench: $(STAMP)
	PYTHONPATH=. $(PY) benchmarks/bench_solver.py

bench-node: $(STAMP)
	PYTHONPATH=. $(PY) benchmarks/bench_node.py $(BENCH_ARGS)

bench-stream: $(STAMP)
	PYTHONPATH=. $(PY) benchmarks/bench_stream.py $(BENCH_ARGS)

bench-soak: $(STAMP)
	PYTHONPATH=. $(PY) benchmarks/bench_soak.py

clean:
	rm -rf $(VENV) out
