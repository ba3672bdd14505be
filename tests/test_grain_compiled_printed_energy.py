"""The compiled grain engine on an impact that gains energy: the needle of test_grain_motion_closed_forms.py (5:1:1,
tumbling onto a still plate under the printed law with e = lam = 0.9, which gains 5 % kinetic energy there) gets
both warnings of the law, the second with the energies before and after written by hand from the impact log."""
import pytest

from symmech.grain.motion_engine import driver as compiled
from test_grain_motion_closed_forms import needle, needle_energies, numerics

pytestmark = [pytest.mark.slow, pytest.mark.compiled_engine]  # the engine's build: slow tier (conftest.py)


def test_the_printed_laws_energy_gain_is_warned_with_its_energies():
    model, st = needle()
    res = compiled.simulate(model, numerics(), st, 1e-5)
    imp = res.impacts[0]
    ke0, ke1 = needle_energies(model, imp)
    assert ke1 > 1.04 * ke0 and imp["printed_creates_energy"] is True
    assert res.warnings[:2] == ["printed impact law: no admissible root; the one used creates kinetic energy",
                                f"impact law 'printed' created energy: {ke0:.6g} J -> {ke1:.6g} J"]
