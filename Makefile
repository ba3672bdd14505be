.PHONY: install codegen check test slow bench mutate
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

# mutation testing, not in the default suite: every shard of tests/mutate.py one after the other, or
# MODULE=symmech/trolley/membrane.py (or a shard name) alone; results and triage in docs/mutation.md
mutate:
	$(PY) tests/mutate.py $(MODULE)
