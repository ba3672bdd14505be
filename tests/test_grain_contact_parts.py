"""The grain's contact search against closed forms: the lower parabola's clear span, a piece proven by one end
only, and a gap h(t) = c (t - 1/2)^2 / 2 - delta that dips below zero between two scan samples (its first zero
1/2 - sqrt(2 delta / c)), found by both searches."""
import math

import numpy as np
import pytest

from symmech.grain import contact

C, DELTA = 1.0, 1e-3  # the dip's curvature [m/s^2] and depth [m]
ROOT = 0.5 - math.sqrt(2 * DELTA / C)


def gap_and_rate(t):
    return 0.5 * C * (t - 0.5) ** 2 - DELTA, C * (t - 0.5)


def test_clear_span_is_the_lower_parabolas_first_zero():
    # h + r s - c s^2 / 2 = 0: 1 - s - s^2 / 2 = 0 at s = sqrt(3) - 1; no curvature: h / -r, or never
    assert contact.clear_span(1.0, -1.0, 1.0) == pytest.approx(math.sqrt(3) - 1, rel=1e-15)
    assert contact.clear_span(2.0, -0.5, 0.0) == 4.0
    assert contact.clear_span(2.0, 0.0, 0.0) == math.inf  # a gap that neither closes nor bends stays open
    assert contact.clear_span(2.0, 0.5, 0.0) == math.inf


def test_a_piece_is_clear_when_either_end_proves_it_else_halved_down_to_xtol():
    # from a: h = 1, level, no curvature: h >= 1 on the piece; from b (rising at b): 1e-6 - 10 < 0 proves nothing
    assert contact.parabolas_clear(1.0, 0.0, 1e-6, 10.0, 1.0, 0.0)
    assert contact.parabolas_clear(1e-6, -10.0, 1.0, 0.0, 1.0, 0.0)
    assert not contact.parabolas_clear(1e-6, -10.0, 1e-6, 10.0, 1.0, 0.0)
    # a level gap of 1 mm under a curvature bound of 1e6 m/s^2 is never cleared: over a step of 1 s at xtol = 1/4 s
    # it is sampled at 0, 1, then halved to pieces of 1/4 s (exact in binary) and no further: 1/2, 1/4, 3/4
    times = []

    def level(t):
        times.append(t)
        return 1e-3, 0.0

    assert contact.first_contact(level, 1e6, 0.0, 1.0, 1.0, 0.25) is None
    assert times == [0.0, 1.0, 0.5, 0.25, 0.75]


@pytest.mark.parametrize("t0", [0.0, -10.0])
def test_a_dip_between_two_samples_is_found_by_the_exact_flights_search(t0):
    """Samples at t0 and t0 + 0.6 are both above the plane: only halving the piece finds the dip, whatever the clock
    reads at the start (a flight from t0 = -10 s, the same gap shifted)."""
    assert gap_and_rate(0.6)[0] > 0

    calls = []

    def shifted(t):
        calls.append(t)
        return gap_and_rate(t - t0)

    # to a coarse xtol the halving stops where a piece's parabolas clear it: 12 evaluations (halving every piece
    # down to 1e-3 s, as a bound read at the wrong span would, takes hundreds)
    assert contact.first_contact(shifted, C, t0, t0 + 1.0, 0.6, 1e-3) == pytest.approx(t0 + ROOT, abs=1e-3)
    assert len(calls) <= 16
    assert contact.first_contact(shifted, C, t0, t0 + 1.0, 0.6, 1e-12) == pytest.approx(t0 + ROOT, abs=1e-11)


def test_a_dip_between_two_samples_is_found_by_the_reference_flights_scan():
    def h(t):
        return gap_and_rate(np.asarray(t, dtype=float))[0]

    assert contact.first_root(h, 0.0, 1.0, 0.3, 1e-12) == pytest.approx(ROOT, abs=1e-11)


def test_the_reference_scan_samples_windows_of_32_steps_and_refines_to_the_callers_xtol():
    """The compiled engine's scan takes the same samples (t0 + k step in windows of 32 steps, each next window from
    the last one's second-to-last sample) and the same Brent refinement: cos t from 0 at step 0.01 is sampled in
    windows starting at 0, 0.31, 0.62, ...; at step 0.3 it falls through zero between 1.5 and 1.8, refined to 1e-3
    s (a finer refinement gives another number)."""
    from scipy.optimize import brentq

    windows = []

    def cos(t):
        if np.ndim(t):
            windows.append(np.asarray(t))
        return np.cos(t)

    assert contact.first_root(cos, 0.0, 3.0, 0.01, 1e-12) == pytest.approx(math.pi / 2, abs=1e-12)
    assert [w.size for w in windows] == [33] * len(windows)
    np.testing.assert_allclose([w[0] for w in windows], 0.31 * np.arange(len(windows)), rtol=1e-12)
    np.testing.assert_allclose(windows[1], 0.31 + 0.01 * np.arange(33), rtol=1e-12)
    coarse = contact.first_root(cos, 0.0, 3.0, 0.3, 1e-3)
    assert coarse == brentq(np.cos, 0.3 * 5, 0.3 * 6, xtol=1e-3)
    assert abs(coarse - math.pi / 2) <= 1e-3


def test_a_gap_that_touches_the_plane_at_a_sample_is_a_contact_there():
    """h = (t - 1/2)², sampled at 0 and 1/2 (step 1/2, the parabola from 0 clears only 0.207 s): h reaches zero
    exactly at the sample t = 1/2 and rises after; the first contact is that sample."""
    def touching(t):
        return (t - 0.5) ** 2, 2.0 * (t - 0.5)

    assert contact.first_contact(touching, 2.0, 0.0, 1.0, 0.5, 1e-12) == 0.5
