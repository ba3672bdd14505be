.PHONY: install codegen check test bench
PY ?= python

install:
	$(PY) -m pip install -e ".[test]"

codegen:
	$(PY) -m symmech codegen

check:
	$(PY) -m symmech codegen --check

test:
	$(PY) -m pytest

bench:
	for f in benchmarks/bench_*.py; do $(PY) $$f || exit 1; done
