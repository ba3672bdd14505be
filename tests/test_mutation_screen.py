"""The mutation screen's verdicts (tools/mutation_screen.py) on made-up test files whose outcome is known, and its
record's change hash, table, sample intervals and renames (tools/mutation_record.py): a failing test kills, on an
assertion (`killed`) or on another exception (`raised`), told apart; a fixture error, a collection error, a crash
and a timeout each get their own outcome, none a kill."""
import sys
import textwrap
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tools"))
import mutate  # noqa: E402
import mutation_record as rec  # noqa: E402
import mutation_screen  # noqa: E402

pytestmark = pytest.mark.xdist_group("test_mutation_screen")
QUIET = ["-q", "-p", "no:cacheprovider", "-p", "no:xdist", "-p", "no:hypothesispytest"]  # a bare pytest starts faster

CASES = {
    "assertion": ("def test_a():\n    pass\n\ndef test_b():\n    assert 1 + 1 == 3\n", "killed", "test_b"),
    "raises_mismatch": ("import pytest\n\ndef test_a():\n    with pytest.raises(ValueError):\n        pass\n",
                        "killed", "test_a"),
    "other_exception": ("def test_a():\n    None + 1\n", "raised", "test_a (TypeError)"),
    # past a test that raises, the screen runs on: a later assertion kills, as a raise does not
    "raise_then_assert": ("def test_a():\n    {}['k']\n\ndef test_b():\n    assert False\n", "killed",
                          "test_b"),
    "raise_then_pass": ("def test_a():\n    {}['k']\n\ndef test_b():\n    pass\n", "raised",
                        "test_a (KeyError)"),
    "fixture_then_assert": ("import pytest\n\n@pytest.fixture\ndef f():\n    raise OSError\n\ndef test_a(f):\n"
                            "    pass\n\ndef test_b():\n    assert False\n", "killed", "test_b"),
    # it stops at the first assertion, as -x would
    "assert_then_raise": ("def test_a():\n    assert False\n\ndef test_b():\n    {}['k']\n", "killed", "test_a"),
    "fixture": ("import pytest\n\n@pytest.fixture\ndef f():\n    raise OSError\n\ndef test_a(f):\n    pass\n",
                "error", "test_a (setup: OSError)"),
    "collection": ("import no_such_module_here\n\ndef test_a():\n    pass\n", "collection", None),
    "passing": ("def test_a():\n    assert True\n", "survived", ""),
    "crash": ("import os, signal\n\ndef test_a():\n    os.kill(os.getpid(), signal.SIGKILL)\n", "crash", ""),
}


# each case is a pytest process (~1 s): the default tier runs one per outcome, the slow tier the orderings too
ORDERINGS = {"raises_mismatch", "raise_then_assert", "raise_then_pass", "fixture_then_assert", "assert_then_raise"}


@pytest.mark.parametrize("case", [c if c not in ORDERINGS else pytest.param(c, marks=pytest.mark.slow)
                                  for c in sorted(CASES)])
def test_each_outcome_is_told_apart(tmp_path, case):
    source, outcome, test = CASES[case]
    path = tmp_path / f"test_{case}.py"
    path.write_text(source)
    # the rootdir pinned: test ids are relative to it, wherever the clone and the temporary folder are
    got, decided, _ = mutation_screen.run_one("", [str(path), f"--rootdir={tmp_path}", *QUIET], 60.0)
    assert got == outcome
    if test is not None:
        assert decided == (f"{path.name}::{test}" if test else "")


def test_a_run_past_its_limit_is_a_timeout(tmp_path):
    path = tmp_path / "test_slow.py"
    path.write_text("import time\n\ndef test_a():\n    time.sleep(30)\n")
    outcome, _, seconds = mutation_screen.run_one("", [str(path), *QUIET], 1.0)
    assert outcome == "timeout" and 1.0 <= seconds < 10.0


@pytest.mark.slow
def test_a_raise_before_a_test_that_hangs_is_a_kill_by_a_raise(tmp_path):
    """The screen runs on past a raise (a later test may assert); a later test past the limit leaves the raise."""
    path = tmp_path / "test_raise_then_hang.py"
    path.write_text("import time\n\ndef test_a():\n    {}['k']\n\ndef test_b():\n    time.sleep(30)\n")
    outcome, decided, seconds = mutation_screen.run_one("", [str(path), f"--rootdir={tmp_path}", *QUIET], 3.0)
    assert (outcome, decided) == ("raised", f"{path.name}::test_a (KeyError)") and seconds < 10.0


def test_a_recheck_runs_the_deciding_test_with_the_selections_marks_and_options(tmp_path):
    kill = rec.Entry("m.x_f__mutmut_1", "s", "0123456789ab", "raised", "tests/test_a.py::test_b (TypeError)", 1.0, "")
    args = mutation_screen.deciding(kill, tmp_path, ["tests/test_a.py", "--noconftest", "-m", "not slow", "-k", "b"])
    assert args[:4] == [str(tmp_path / "frozen" / "tests/test_a.py::test_b"), "-m", "not slow", "--noconftest"]
    assert mutation_screen.deciding(rec.Entry("m.x_f__mutmut_2", "s", "ab", "survived", "", 1.0, ""), tmp_path,
                                    ["tests/test_a.py"]) == []
    both = mutation_screen.node_args(["tests/test_a.py::test_b", "tests/test_c.py::test_d[1]"], tmp_path,
                                     ["tests/test_a.py", "-m", "slow"])
    assert both[:4] == [str(tmp_path / "frozen" / "tests/test_a.py::test_b"),
                        str(tmp_path / "frozen" / "tests/test_c.py::test_d[1]"), "-m", "slow"]


def test_the_table_counts_both_kinds_of_kill_and_each_non_kill_apart(tmp_path, monkeypatch):
    """Six mutants of a full record: 2 killed by an assertion, 1 by a raise (3 of 6, 50 %), a survivor, a fixture
    error and a timeout, each in its column; no proof, so 50 % of the non-equivalent too."""
    monkeypatch.setattr(rec, "RESULTS", tmp_path)
    monkeypatch.setattr(rec, "EQUIVALENT", tmp_path / "none.tsv")
    outcomes = ["killed", "killed", "raised", "survived", "error", "timeout"]
    entries = {f"m.x_f__mutmut_{i}": rec.Entry(f"m.x_f__mutmut_{i}", "s", f"{i:012x}", o, "", 1.0, "")
               for i, o in enumerate(outcomes)}
    rec.write(tmp_path / "m.tsv", entries, ["made: 6 mutants of m.py by mutmut"])
    row = next(line for line in rec.table(["m.py"]).splitlines() if line.startswith("| `m`"))
    assert row == "| `m` | 6 (6) | full | 2 | 1 | 3 (50.0 %) | 0 | 1 | 1 | 0 | 0 | 1 | 0 | 50.0 % |"


def test_change_hash_ignores_the_diff_header_and_indentation():
    diff = textwrap.dedent("""\
        --- a.py
        +++ a.py
        @@ -1,2 +1,2 @@
         def f(x):
        -    return x + 1
        +    return x - 1""")
    digest, summary = rec.change_of(diff)
    assert summary == "return x + 1 → return x - 1"
    assert rec.change_of(diff.replace("a.py", "b.py").replace("    return", "  return"))[0] == digest
    assert rec.change_of(diff.replace("x - 1", "x * 1"))[0] != digest


def test_proven_survivors_count_as_equivalent_and_nothing_else_does():
    entries = {f"m.x_f__mutmut_{i}": rec.Entry(f"m.x_f__mutmut_{i}", "s", h, o, "", 1.0, "")
               for i, (h, o) in enumerate([("a", "survived"), ("b", "survived"), ("c", "killed"), ("d", "timeout"),
                                           ("e", "raised")])}
    proofs = {("m", "x_f", "a"): "proof", ("m", "x_f", "c"): "a proof of a killed mutant is moot",
              ("other", "x_f", "b"): "elsewhere"}
    counts = rec.tally(entries, "m", proofs)
    assert {k: v for k, v in counts.items() if v} == {"equivalent": 1, "survived": 1, "killed": 1, "timeout": 1,
                                                       "raised": 1}
    # the same change in another function of the module is another mutant: the proof of x_f's does not cover it
    assert rec.tally(entries, "m", {("m", "x_g", "a"): "a proof of x_g's change"})["equivalent"] == 0


def test_a_record_survives_a_write_and_read(tmp_path):
    entries = {"m.x_f__mutmut_10": rec.Entry("m.x_f__mutmut_10", "s", "0123456789ab", "killed", "t.py::test_a", 2.5,
                                             "a → b"),
               "m.x_f__mutmut_9": rec.Entry("m.x_f__mutmut_9", "s", "ba9876543210", "survived", "", 3.25, "c → d")}
    path = tmp_path / "m.tsv"
    rec.write(path, entries, ["shard s: a note"])
    assert rec.read(path) == entries
    assert rec.notes_of(path) == ["shard s: a note"]
    assert [line.split("\t")[0] for line in path.read_text().splitlines()[2:]] == ["m.x_f__mutmut_9", "m.x_f__mutmut_10"]
    # a shard that only screened the record's mutants again (its lines are another shard's draw) is told from one
    # that screened mutants of its own, later again too
    again = f"({mutation_screen.AGAIN}): a note"
    rec.write(path, entries, ["shard s (the rest of its sample): a note", f"shard table {again}", "shard part: a note",
                              f"shard part {again}", f"shard table {again}"])
    assert mutate.rescreen_shards(path) == {"table"}


def test_a_change_made_at_several_places_finds_each_recorded_mutant_its_own():
    """`continue` → `break` at three places of f (one hash): the recorded _62 is found as _62 while f still makes
    that change there, as the place nearest its number (_63) after an edit moved it, and never as _37 or _49; a
    change no longer made finds nothing."""
    def entry(name, digest):
        return rec.Entry(name, "s", digest, "survived", "", 1.0, "continue → break")

    old = [entry("old.path.x_f__mutmut_62", "aaaaaaaaaaaa"), entry("old.path.x_f__mutmut_7", "bbbbbbbbbbbb")]
    places = {f"m.x_f__mutmut_{n}": ("x_f", "aaaaaaaaaaaa") for n in (37, 49, 62)}
    assert rec.match(old, places) == {"old.path.x_f__mutmut_62": "m.x_f__mutmut_62"}
    moved = {f"m.x_f__mutmut_{n}": ("x_f", "aaaaaaaaaaaa") for n in (38, 50, 63)}
    assert rec.match(old, moved) == {"old.path.x_f__mutmut_62": "m.x_f__mutmut_63"}


def test_a_screen_after_an_edit_keeps_every_recorded_line_under_its_current_name():
    """An edit inserted a mutant at _1 of f: the recorded _1 and _2 are now _2 and _3, and the new _1 is screened.
    Every kept line moves to its current name first, so the new _1 overwrites none of them; a stale line goes."""
    def entry(name, digest, outcome):
        return rec.Entry(name, "s", digest, outcome, "", 1.0, "a → b")

    recorded = {"m.x_f__mutmut_1": entry("m.x_f__mutmut_1", "aaaaaaaaaaaa", "killed"),
                "m.x_f__mutmut_2": entry("m.x_f__mutmut_2", "bbbbbbbbbbbb", "survived"),
                "m.x_f__mutmut_9": entry("m.x_f__mutmut_9", "cccccccccccc", "raised")}
    current = {"m.x_f__mutmut_1": ("x_f", "dddddddddddd"), "m.x_f__mutmut_2": ("x_f", "aaaaaaaaaaaa"),
               "m.x_f__mutmut_3": ("x_f", "bbbbbbbbbbbb")}
    found = rec.match(list(recorded.values()), current)
    kept = mutation_screen.kept(recorded, found, ("m.x_f__mutmut_9",))
    assert {n: (e.mutant, e.hash, e.outcome) for n, e in kept.items()} == {
        "m.x_f__mutmut_2": ("m.x_f__mutmut_2", "aaaaaaaaaaaa", "killed"),
        "m.x_f__mutmut_3": ("m.x_f__mutmut_3", "bbbbbbbbbbbb", "survived")}


def test_clopper_pearson_interval_at_its_closed_forms():
    """k = 0 and k = n have closed forms: the upper end 1 - (alpha/2)^(1/n), the lower end (alpha/2)^(1/n); k = 20 of
    40 is symmetric about 1/2 (the ends are the 2.5 % and 97.5 % points of Beta(20, 21) and Beta(21, 20))."""
    assert rec.binomial_interval(0, 40) == (0.0, pytest.approx(1 - 0.025 ** (1 / 40), rel=1e-12))
    assert rec.binomial_interval(40, 40) == (pytest.approx(0.025 ** (1 / 40), rel=1e-12), 1.0)
    low, high = rec.binomial_interval(20, 40)
    assert low + high == pytest.approx(1.0, abs=1e-12) and 0.33 < low < 0.35  # 0.3380, as R's binom.test gives


def test_a_renamed_module_keeps_its_record_and_proofs(tmp_path, monkeypatch):
    """--rename: the record file, its module line, its mutants' names and its proofs' module follow the new path;
    the outcomes, hashes and the equivalent count stay; mutate-check's key (the function's name) is the same."""
    monkeypatch.setattr(rec, "RESULTS", tmp_path / "results")
    monkeypatch.setattr(rec, "EQUIVALENT", tmp_path / "equivalent.tsv")
    old = "symmech.core.ode.x_f__mutmut_3"
    entries = {old: rec.Entry(old, "ode", "0123456789ab", "survived", "", 1.0, "a → b"),
               "symmech.core.ode.xǁCǁm__mutmut_1": rec.Entry("symmech.core.ode.xǁCǁm__mutmut_1", "ode",
                                                               "ba9876543210", "killed", "t.py::test_a", 1.0, "c → d")}
    rec.write(rec.record_path("symmech/core/ode.py"), entries, ["made: 9 mutants of symmech/core/ode.py by mutmut"])
    (tmp_path / "equivalent.tsv").write_text("module\thash\tmutant\tproof\n"
                                             f"symmech.core.ode\t0123456789ab\t{old}\tthe same\n", "utf-8")
    rec.rename("symmech/core/ode.py", "symmech/core/numerics/ode.py")
    path = rec.record_path("symmech/core/numerics/ode.py")
    assert [p.name for p in (tmp_path / "results").iterdir()] == [path.name]
    moved = rec.read(path)
    assert sorted(moved) == ["symmech.core.numerics.ode.x_f__mutmut_3", "symmech.core.numerics.ode.xǁCǁm__mutmut_1"]
    assert rec.notes_of(path) == ["made: 9 mutants of symmech/core/numerics/ode.py by mutmut",
                                  "module: symmech/core/numerics/ode.py"]
    assert rec.tally(moved, "symmech.core.numerics.ode", rec.equivalents())["equivalent"] == 1
    assert {rec.function_of(n) for n in moved} == {rec.function_of(n) for n in entries} == {"x_f", "xǁCǁm"}


def test_check_reads_every_module_named_and_its_options():
    """`--check MODULE ...` checks the records named (the first one too), all of them when none is named."""
    assert mutate.check_arguments(["symmech.a", "symmech.b"]) == (30, 0, ["symmech.a", "symmech.b"])
    assert mutate.check_arguments(["--killed", "5", "symmech.a", "--seed", "3"]) == (5, 3, ["symmech.a"])
    assert mutate.check_arguments([]) == (30, 0, [])


def test_a_kill_whose_deciding_test_was_renamed_is_rerun_against_the_whole_selection(tmp_path, capsys):
    """mutate-check reruns a recorded kill against the test that made it; when the selection no longer holds that
    test (renamed here), pytest would refuse its node id (exit 4, once read as a crash): the kill is rerun against
    the whole selection ([]), and the check says so. A kill whose test is there keeps it; a survivor takes all."""
    def entry(n, outcome, test):
        return rec.Entry(f"m.x_f__mutmut_{n}", "s", f"{n:012x}", outcome, test, 1.0, "")

    chosen = [entry(1, "killed", "tests/test_a.py::test_b[1]"), entry(2, "raised", "tests/test_a.py::test_old (KeyError)"),
              entry(3, "survived", "")]
    got = mutation_screen.reruns(chosen, {"tests/test_a.py::test_b[1]", "tests/test_a.py::test_new"}, tmp_path,
                                 ["tests/test_a.py", "-m", "not slow"])
    assert got == {"m.x_f__mutmut_1": [str(tmp_path / "frozen" / "tests/test_a.py::test_b[1]"), "-m", "not slow", "-q",
                                       "-n", "0", "-p", "no:cacheprovider", "--tb=no"],
                   "m.x_f__mutmut_2": [], "m.x_f__mutmut_3": []}
    assert capsys.readouterr().out == ("    m.x_f__mutmut_2: its deciding test tests/test_a.py::test_old is not in the "
                                       "selection any more (renamed or removed): rerun against the whole selection\n")


def test_a_mutants_limit_is_ten_times_the_median_unmutated_run_at_least_a_minute():
    """The driver's first unmutated run built numba's cache (705 s, then 18 and 30 s): the limit is 10 x 30 s, not
    10 x 705 s; short runs get the 60 s floor."""
    assert mutation_screen.time_limit([705.3, 18.5, 30.3]) == pytest.approx(303.0, rel=1e-12)
    assert mutation_screen.time_limit([1.0, 2.0, 3.0]) == 60.0
