"""Errata coverage: every seed states what is compared and what is not; the SMM general
formulas (seed 003, sections 2-3, Tables 1-2, Figs. 8-9, eqs. (1)-(11)) against derivations."""
import re

import numpy as np
import pytest

from symmech.core import errata
from symmech.smm import errata_general

STEMS = {"000_b52a2f612feb4113", "002_7fa2a0a5477072ec", "003_6166172b9b245651"}


# its module fixture is built once per xdist worker: one worker runs the module, and `errata --json`
# (tests/test_cli_impact.py) in the same worker shares the checks' cached sympy work
pytestmark = pytest.mark.xdist_group("errata")


@pytest.fixture(scope="module")
def records():
    return [errata.evaluate(c, n=60) for c in errata.all_checks()]


def test_seed_ids_are_the_seed_file_stems(records):
    seeds = {r["seed"] for r in records} | {n.seed for n in errata.all_not_compared()}
    assert seeds == STEMS
    assert all(re.fullmatch(r"\d{3}_[0-9a-f]{16}", s) for s in seeds)


def test_coverage_per_seed_adds_up(records):
    cov = errata.coverage(records, errata.all_not_compared())
    assert set(cov) == STEMS
    for c in cov.values():
        assert c["inventoried"] == c["compared"] + len(c["not_compared"])
        assert c["compared"] == c["agree"] + c["differ"]
        assert all(n["reason"] for n in c["not_compared"])
    smm = cov["003_6166172b9b245651"]
    assert smm["compared"] >= 25 and smm["differ"] == 4
    text = errata.coverage_report(cov)
    assert text.count("printed items inventoried") == 3


def test_smm_general_formulas_found_exactly_these_misprints():
    found = {}
    for c in errata_general.checks():
        r = errata.evaluate(c, n=100)
        found[(r["equation"], r["description"])] = r
    differs = {eq for (eq, _), r in found.items() if r["status"] == "differs"}
    # The literal indices of the mixed derivative and of (10), the repeated gravity term of Fig. 8,
    # and (9) applied to a preloaded mechanism with gravity.
    assert sorted(differs) == ["(10)", "(9)", "Fig. 8", "sec. 3 d2l/dq1dq2"]
    for r in found.values():
        if r["status"] == "differs":
            assert r["max_rel_diff"] > 1e-3
        else:
            assert r["max_rel_diff"] < 1e-12
    # each misprint has a reading that agrees, except (9), whose difference is the physics it omits
    agree = {eq for (eq, _), r in found.items() if r["status"] == "agrees"}
    assert {"(10)", "(9)", "Fig. 8", "sec. 3 d2l/dq1dq2"} <= agree


def test_fig8_reading_at_a_hand_point():
    """Fig. 8 at alpha = beta = 45 deg (spring perpendicular to the pendulum): the bracket reduces to
    L^2/l * 0 - 0 = 0, so C = c1 L^2 - m g L sin 45 deg."""
    from symmech.generated import smm_formulas

    c1, L, ell, m, g = 2.0e4, 1.5, 0.8, 12.0, 9.81
    a = b = 0.25 * 3.141592653589793
    expected = c1 * L**2 - m * g * L * 2**-0.5
    assert smm_formulas.fig8_c(c1, L, a, b, ell, m, g) == pytest.approx(expected, rel=1e-12)


def test_trolley_rigid_body_equations_11_agree_with_newton_euler():
    from symmech.trolley import errata as trolley_errata

    (check,) = [c for c in trolley_errata.checks() if c.equation == "(11)"]
    r = errata.evaluate(check, n=200)
    assert r["status"] == "agrees" and r["max_rel_diff"] < 1e-12
    # the sampled motions exercise the gyroscopic terms: without rotation the forces change by > 1 N
    x = check.sample(np.random.default_rng(0), 5)
    still = dict(x, w1=0 * x["w1"], w2=0 * x["w2"], w3=0 * x["w3"])
    assert np.abs(np.asarray(check.printed(x)) - np.asarray(check.printed(still))).max() > 1.0
