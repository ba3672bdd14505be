"""The committed record of mutation screens: one TSV per module in mutation/results/, the equivalence proofs in
mutation/equivalent.tsv, and the per-module table of docs/mutation.md written from them.

A record line is one mutant: its mutmut name, the shard that screened it, the hash and one-line summary of its
change (so that a renumbered mutant is found again), the outcome and the test that decided it. Outcomes:

    killed      a test failed on an assertion (AssertionError, or pytest's own failure: `pytest.raises` that
                did not raise, `pytest.fail`)
    raised      no assertion failed, but a test failed (in its call phase) on another exception the mutated
                code raised
    survived    every test passed
    timeout     stopped after the screen's time limit (a multiple of the unmutated runs' median of 3)
    crash       the test process died (a signal) or left no verdict
    collection  the tests could not be collected (an import of the mutated code failed)
    error       a fixture's setup or teardown failed, no test failed
    no-tests    the selection ran no test

A mutant is killed when a test of its selection fails: "killed" (by an assertion) and "raised" (by a raise) both
count, each in its own column beside their sum, the kill rate (the convention of PIT and Stryker). Timeouts,
crashes, collection errors, fixture errors and no tests are not kills, each in its own column. A survivor named in
mutation/equivalent.tsv with a written proof (no input the code can receive tells it from the original) is
counted apart as equivalent.
"""
from __future__ import annotations

import csv
import hashlib
from dataclasses import dataclass, replace
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "mutation" / "results"
EQUIVALENT = ROOT / "mutation" / "equivalent.tsv"
DOC = ROOT / "docs" / "mutation.md"
OUTCOMES = ("killed", "raised", "survived", "timeout", "crash", "collection", "error", "no-tests")
KILLS = ("killed", "raised")  # a test of the selection failed: on an assertion, or on the mutated code's raise
COLUMNS = ("mutant", "shard", "hash", "outcome", "test", "seconds", "change")
TABLE_START = "<!-- per-module table: written by `python tools/mutate.py --table` from mutation/results/ -->"
TABLE_END = "<!-- end of the per-module table -->"


@dataclass(frozen=True)
class Entry:
    """One mutant's screened outcome."""

    mutant: str  # mutmut's name, "<module>.x_<function>__mutmut_<n>" or "<module>.xǁ<Class>ǁ<method>__mutmut_<n>"
    shard: str
    hash: str  # of the change (the diff's removed and added lines), 12 hex digits
    outcome: str
    test: str  # the test that killed it, or the first that raised or errored; "" otherwise
    seconds: float  # wall time of its screen
    change: str  # "old line → new line", stripped, at most 160 characters


def change_of(diff: str) -> tuple[str, str]:
    """(hash, one-line summary) of a mutant's unified diff against its original function."""
    removed = [line[1:].strip() for line in diff.splitlines() if line.startswith("-") and not line.startswith("---")]
    added = [line[1:].strip() for line in diff.splitlines() if line.startswith("+") and not line.startswith("+++")]
    digest = hashlib.sha1("\n".join(["-", *removed, "+", *added]).encode()).hexdigest()[:12]
    old, new = " / ".join(removed), " / ".join(added)
    same = next((i for i, (a, b) in enumerate(zip(old, new)) if a != b), min(len(old), len(new)))
    tail = next((i for i, (a, b) in enumerate(zip(old[same:][::-1], new[same:][::-1])) if a != b),
                min(len(old), len(new)) - same)
    if len(old) + len(new) > 150:  # the change in brackets, 40 characters of context either side
        old_part, new_part = old[same:len(old) - tail], new[same:len(new) - tail]
        before, after = old[:same][-40:], old[len(old) - tail:][:40]
        return digest, f"…{before}[{old_part} → {new_part}]{after}…"
    return digest, f"{old} → {new}"


def record_path(module: str) -> Path:
    """mutation/results/<dotted module>.tsv for a module path such as symmech/grain/coulomb_law.py."""
    return RESULTS / (module.removesuffix(".py").replace("/", ".") + ".tsv")


def read(path: Path) -> dict[str, Entry]:
    """A record's entries by mutant name (later lines replace earlier ones)."""
    if not path.exists():
        return {}
    with path.open(encoding="utf-8", newline="") as f:
        rows = csv.DictReader((line for line in f if not line.startswith("#")), delimiter="\t")
        return {r["mutant"]: Entry(r["mutant"], r["shard"], r["hash"], r["outcome"], r["test"], float(r["seconds"]),
                                   r["change"]) for r in rows}


def write(path: Path, entries: dict[str, Entry], notes: list[str]) -> None:
    """Write a record atomically, sorted by mutant (function, then number), with `notes` as # lines on top."""
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_suffix(".tsv.tmp")
    with tmp.open("w", encoding="utf-8", newline="") as f:
        f.writelines(f"# {note}\n" for note in notes)
        out = csv.writer(f, delimiter="\t", lineterminator="\n")
        out.writerow(COLUMNS)
        for e in sorted(entries.values(), key=lambda e: order(e.mutant)):
            out.writerow([e.mutant, e.shard, e.hash, e.outcome, e.test, f"{e.seconds:.2f}", e.change])
    tmp.replace(path)


def notes_of(path: Path) -> list[str]:
    """The # lines of a record, without the '# '."""
    if not path.exists():
        return []
    return [line[2:].rstrip("\n") for line in path.read_text("utf-8").splitlines(True) if line.startswith("# ")]


def order(mutant: str) -> tuple[str, int]:
    """Sort key of a mutant name: its function, then its number."""
    function, _, number = mutant.rpartition("__mutmut_")
    return function, int(number) if number.isdigit() else 0


def shards_of(path: Path) -> set[str]:
    """The shards whose screens wrote a record's entries."""
    return {e.shard for e in read(path).values()}


def equivalents() -> dict[tuple[str, str, str], str]:
    """The written proofs: (dotted module, function, change hash) -> proof. The function is part of the key: the
    same line changed the same way in another function (`np.asarray(q, dtype=float)` in two functions) is another
    mutant, which a proof of the first does not cover."""
    if not EQUIVALENT.exists():
        return {}
    with EQUIVALENT.open(encoding="utf-8", newline="") as f:
        rows = csv.DictReader((line for line in f if not line.startswith("#")), delimiter="\t")
        return {(r["module"], function_of(r["mutant"]), r["hash"]): r["proof"] for r in rows}


def is_proven(entry: Entry, module: str, proofs: dict[tuple[str, str, str], str]) -> bool:
    """Whether a recorded survivor of `module` has a written proof of its own function's change."""
    return entry.outcome == "survived" and (module, function_of(entry.mutant), entry.hash) in proofs


def tally(entries: dict[str, Entry], module: str, proofs: dict[tuple[str, str, str], str]) -> dict[str, int]:
    """Counts per outcome, with the proven-equivalent survivors as "equivalent" (not "survived")."""
    counts = dict.fromkeys((*OUTCOMES, "equivalent"), 0)
    for e in entries.values():
        counts["equivalent" if is_proven(e, module, proofs) else e.outcome] += 1
    return counts


def function_of(mutant: str) -> str:
    """The function part of a mutant's name, without its module ("x_f" or "xǁClassǁmethod"): what stays when
    the module moves (a record keyed by the old path still finds its mutants in the new one)."""
    return mutant.rpartition("__mutmut_")[0].rpartition(".")[2]


def match(entries: list[Entry], current: dict[str, tuple[str, str]]) -> dict[str, str]:
    """Recorded mutant name -> the current mutant making the same change (`current`: name -> (function, change
    hash)); the numbers move when the module is edited, the module's path when it moves. A change a function makes
    at several places (`continue` → `break`) has one current mutant per place: each recorded mutant keeps its own
    function and number when they still make the change, else takes the unclaimed one nearest its number."""
    places: dict[tuple[str, str], list[str]] = {}
    for name, key in current.items():
        places.setdefault(key, []).append(name)
    found: dict[str, str] = {}
    claimed: set[str] = set()

    def number(name: str) -> int:
        return order(name)[1]

    def same_place(e: Entry) -> str | None:
        return next((n for n in places.get((function_of(e.mutant), e.hash), [])
                     if number(n) == number(e.mutant)), None)

    for e in sorted(entries, key=lambda e: same_place(e) is None):
        left = [n for n in places.get((function_of(e.mutant), e.hash), []) if n not in claimed]
        name = same_place(e) if same_place(e) in left else min(left, key=lambda n: abs(number(n) - number(e.mutant)),
                                                                default=None)
        if name is not None:
            found[e.mutant] = name
            claimed.add(name)
    return found


def made_of(path: Path) -> str:
    """How many mutants mutmut made of the record's module (its "made:" note; "?" without one)."""
    return next((note.split()[1] for note in notes_of(path) if note.startswith("made:")), "?")


def sample_note(path: Path) -> str:
    """The record's "sample:" note ("" for a record of all, or of named shards of, its module's mutants)."""
    return next((note for note in notes_of(path) if note.startswith("sample:")), "")


def binomial_interval(k: int, n: int, level: float = 0.95) -> tuple[float, float]:
    """Clopper-Pearson interval of a proportion k / n (exact binomial, `level` two-sided)."""
    from scipy.special import betaincinv  # the beta distribution's quantile, without scipy.stats' import time

    alpha = 1.0 - level
    low = 0.0 if k == 0 else float(betaincinv(k, n - k + 1, alpha / 2))
    high = 1.0 if k == n else float(betaincinv(k + 1, n - k, 1 - alpha / 2))
    return low, high


def scope(path: Path, n: int, made: str) -> str:
    """How a record's mutants were chosen: all, a seeded random sample, or the named shards' functions."""
    if sample_note(path):
        return "sample"
    return "full" if not made.isdigit() or n >= int(made) else "part"


def rate(k: int, n: int, sampled: bool) -> str:
    """"k (p %)", with the binomial 95 % interval of the module's rate when the n mutants are a random sample."""
    if not sampled:
        return f"{k} ({100 * k / n:.1f} %)"
    low, high = binomial_interval(k, n)
    return f"{k} ({100 * k / n:.1f} %, {100 * low:.0f}–{100 * high:.0f} %)"


def table(modules: list[str]) -> str:
    """The per-module table (markdown) of every committed record, then the modules of `modules` without one."""
    proofs = equivalents()
    lines = ["| module | mutants screened (made) | sample or full | killed by an assertion | killed by a raise "
             "| killed: kill rate | equivalent, proven | survived | timeout | crash | collection error "
             "| fixture error | no tests | killed, of the non-equivalent |",
             "| --- | ---: | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |"]
    recorded = sorted(RESULTS.glob("*.tsv"))
    partial = []
    for path in recorded:
        module = path.stem
        c = tally(read(path), module, proofs)
        n = sum(c.values())
        made = made_of(path)
        if n == 0:
            continue
        rest = n - c["equivalent"]
        how = scope(path, n, made)
        if how == "part":
            partial.append(f"`{module}` ({n} of {made}: {', '.join(sorted(shards_of(path)))})")
        sampled = how == "sample"
        kills = sum(c[k] for k in KILLS)
        lines.append(f"| `{module}` | {n} ({made}) | {how} | {c['killed']} | {c['raised']} "
                     f"| {rate(kills, n, sampled)} | {c['equivalent']} | {c['survived']} | {c['timeout']} "
                     f"| {c['crash']} | {c['collection']} | {c['error']} | {c['no-tests']} "
                     f"| {100 * kills / rest if rest else 100:.1f} % |")
    lines += ["", "Samples: the rate of the mutants the sample was drawn from (the module's, or one shard's: "
              "the record's `sample:` note gives the seed and the shard), 95 % Clopper-Pearson interval after it. "
              "Records of part of a module "
              "(the named shards' functions, not a random sample: no interval): " + (", ".join(partial) or "none")
              + "."]
    have = {p.stem for p in recorded}
    missing = sorted({m.removesuffix(".py").replace("/", ".") for m in modules} - have)
    lines += ["", "Modules with shards and no committed record yet (their only numbers are those of the earlier "
                  "screens in mutation/history.md, which counted crashes, collection errors and timeouts as kills): "
              + (", ".join(f"`{m}`" for m in missing) or "none") + "."]
    return "\n".join(lines)


def coverage_table(coverage: dict[str, str]) -> str:
    """Every physics and numerics module (path -> "" when screened, else why not) with its record's scope, or why
    it has none."""
    lines = ["| module | record | why not screened, or what is left |", "| --- | --- | --- |"]
    for module, why in coverage.items():
        path = record_path(module)
        n = len(read(path))
        made = made_of(path)
        found = f"{scope(path, n, made)}: {n} of {made}" if n else "none"
        lines.append(f"| `{module}` | {found} | {why or ('—' if n else 'not screened yet')} |")
    return "\n".join(lines)


def write_table(modules: list[str], coverage: dict[str, str]) -> None:
    """Replace the tables between the markers of docs/mutation.md: per record, then per physics module."""
    text = DOC.read_text("utf-8")
    head, _, rest = text.partition(TABLE_START)
    _, _, tail = rest.partition(TABLE_END)
    if not rest:
        raise SystemExit(f"{DOC}: no line {TABLE_START!r} to write the table after")
    tmp = DOC.with_suffix(".md.tmp")
    tables = f"{table(modules)}\n\nEvery module that computes physics or numerics:\n\n{coverage_table(coverage)}"
    tmp.write_text(f"{head}{TABLE_START}\n\n{tables}\n\n{TABLE_END}{tail}", "utf-8")
    tmp.replace(DOC)


def rename(old: str, new: str) -> None:
    """A module moved from path `old` to `new` (symmech/core/ode.py -> symmech/core/numerics/ode.py): its record
    file, its notes, its mutants' names and its proofs' module follow it (the change hashes stay: mutate-check
    finds each mutant again by its function and change)."""
    dotted = [m.removesuffix(".py").replace("/", ".") for m in (old, new)]
    source = record_path(old)
    if not source.exists():
        raise SystemExit(f"{source}: no record of {old}")
    entries = {}
    for e in read(source).values():
        name = e.mutant.replace(dotted[0] + ".", dotted[1] + ".", 1)
        entries[name] = replace(e, mutant=name)
    notes = [note.replace(old, new) for note in notes_of(source) if not note.startswith("module:")]
    notes.insert(1, f"module: {new}")
    write(record_path(new), entries, notes)
    source.unlink()
    if EQUIVALENT.exists():
        text = EQUIVALENT.read_text("utf-8")
        lines = [line.replace(dotted[0], dotted[1]) if line.startswith(dotted[0] + "\t") else line
                 for line in text.splitlines(True)]
        tmp = EQUIVALENT.with_suffix(".tsv.tmp")
        tmp.write_text("".join(lines), "utf-8")
        tmp.replace(EQUIVALENT)
