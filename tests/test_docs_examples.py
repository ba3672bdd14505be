"""The examples of docs/python-api.md run as written (from the repository root) and give what the page says."""
import re
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]


def _blocks(page: str) -> list[str]:
    return re.findall(r"```python\n(.*?)```", (ROOT / "docs" / page).read_text(encoding="utf-8"), flags=re.S)


@pytest.mark.xdist_group("twins")  # compiles the twins test_dynamics_rhs compiles: once, in one worker
def test_python_api_examples_run_and_use_the_compiled_twins(monkeypatch):
    """The first two blocks are programs (the third, the toolkit's, runs in the slow tier; the fourth is a
    fragment of a derivation). The rotor boom's
    solve_ivp on the twin's rhs/jac ends within 1e-9 of the amplitude of the run's matrix-exponential
    response (the page says 3e-10); the grain's p drives the flight rates r'' = g_K + A w^2 d sin(w t + phase)."""
    blocks = _blocks("python-api.md")
    assert len(blocks) == 4 and blocks[3].lstrip().startswith("Dynamics(")
    monkeypatch.chdir(ROOT)
    namespace = {}
    exec(blocks[0] + blocks[1], namespace)
    rb, gm, sol, table = namespace["rb"], namespace["gm"], namespace["sol"], namespace["result"].tables["free_response"]
    assert rb.__name__.endswith("smm_rotor_boom_nb") and gm.__name__.endswith("grain_motion_nb")
    assert sol.success and sol.t[-1] == 2.0
    row = np.flatnonzero(np.isclose(table.data[:, 0], 2.0, rtol=0, atol=1e-12))
    q = table.data[:, 1:3]
    assert len(row) == 1 and np.abs(q).max() > 1e-4
    assert np.abs(sol.y[:2, -1] - q[row[0]]).max() <= 1e-9 * np.abs(q).max()
    p = namespace["p"]
    y, t = np.linspace(0.1, 1.3, 13), 0.37
    A, omega, phase = p[3:6]
    np.testing.assert_allclose(gm.rhs(t, y, p)[3:6], p[0:3] + A * omega**2 * p[6:9] * np.sin(omega * t + phase),
                               rtol=1e-13, atol=1e-12)


@pytest.mark.slow  # the toolkit compiles its solver for the module in each process (~20 s)
def test_python_api_toolkit_example_equals_solve_ivp(monkeypatch, capsys):
    """The compiled-toolkit block integrates the rotor boom; scipy's Radau on the numpy rhs agrees to 1e-8
    of the amplitude at every requested time."""
    from scipy.integrate import solve_ivp

    monkeypatch.chdir(ROOT)
    namespace = {}
    exec(_blocks("python-api.md")[2], namespace)
    sol, rb, p, y0 = namespace["sol"], namespace["rb"], namespace["p"], namespace["y0"]
    ref = solve_ivp(rb.rhs, (0.0, 2.0), y0, t_eval=np.linspace(0.0, 2.0, 201), args=(p,), method="Radau",
                    rtol=1e-11, atol=1e-14)
    assert sol.y.shape == ref.y.shape and sol.steps > 0
    assert np.abs(sol.y - ref.y).max() <= 1e-8 * np.abs(ref.y).max()
