.PHONY: install codegen check test slow bench
PY ?= python

install:
	$(PY) -m pip install -e ".[test]"

codegen:
	$(PY) -m symmech codegen

check:
	$(PY) -m symmech codegen --check

test:
	$(PY) -m pytest

# the slow tests .ci/run adds: wheel install outside the checkout, every precision study, long fuzzing,
# the longer numerical tests
slow:
	$(PY) -m pytest -m slow

bench:
	for f in benchmarks/bench_*.py; do $(PY) $$f || exit 1; done
