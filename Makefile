.PHONY: install codegen check lint test slow bench mutate mutate-check
PY ?= python

install:
	$(PY) -m pip install -e ".[test]"

codegen:
	$(PY) -m symmech codegen

check:
	$(PY) -m symmech codegen --check

# ruff, with the rules pinned in pyproject.toml; .ci/run runs it
lint:
	$(PY) -m ruff check symmech tests benchmarks tools

test:
	$(PY) -m pytest

# the slow tests .ci/run adds: wheel install outside the checkout, every precision study, long fuzzing,
# the longer numerical tests
slow:
	$(PY) -m pytest -m slow

bench:
	for f in benchmarks/bench_*.py; do $(PY) $$f || exit 1; done

# mutation testing, not in the default suite: every shard of tools/mutate.py one after the other through mutmut,
# or MODULE=symmech/trolley/membrane.py (or a shard name) alone; the method in docs/mutation.md
mutate:
	$(PY) tools/mutate.py $(MODULE)

# rerun 30 killed mutants of every committed record (mutation/results/) and every proven-equivalent one against
# the current tree; fails when a recorded outcome no longer holds
mutate-check:
	nice -n 10 $(PY) tools/mutate.py --check
