"""The frame state of the elastic trolley on a helix against the Frenet-Serret closed forms.

The track r(s) = (a sin(s/c), b s/c, a cos(s/c)), arc length s, c = √(a² + b²), axis up (X2): curvature
κ = a/c², torsion from B' = -τ N; with the Frenet frame (x1, x2, x3) = (T, N, B) and the speed V0(t), the
origin moves with v0 = V0 T, a0 = V̇0 T + V0² κ N, the frame turns with ω = V0 (τ T + κ B), ω̇ = V̇0 (τ T + κ B),
and "up" is ν = (T·X2, N·X2, B·X2)."""
import sys
from pathlib import Path

import numpy as np
import pytest

from symmech.trolley import elastic as el
from symmech.trolley import elastic_scene

sys.path.insert(0, str(Path(__file__).parent))
from trolley_util import prepared, setup as scene_dict  # noqa: E402

pytestmark = pytest.mark.xdist_group("test_elastic_frame")

A, B = 7.0, 2.0
C = float(np.hypot(A, B))


def tnb(s):
    """T, N, B (3, 3) of the helix at s, written out."""
    u = s / C
    t = np.array([A * np.cos(u), B, -A * np.sin(u)]) / C
    n = np.array([-np.sin(u), 0.0, -np.cos(u)])
    return np.array([t, n, np.cross(t, n)])


def test_frame_state_on_a_helix_is_the_frenet_serret_motion():
    data = scene_dict(frame="frenet", track={"type": "expression", "x": f"{A}*sin(s/{C!r})", "y": f"{B}*s/{C!r}",
                                             "z": f"{A}*cos(s/{C!r})"},
                      motion={"speed": "3 + 2*t"}, time={"t_end": 1.0, "steps": 10})
    drive = elastic_scene.drive_of(prepared(data), 1)
    system = el.System(el.ElasticModel(100.0, (0, 0, 0), (1, 1, 1, 0, 0, 0), 2.0, 1.0, 9.81,
                                       el.Rollers((1e6,) * 5, (0.0,) * 5)))
    h = 1e-4
    for time, s in ((0.5, 1.3), (0.8, 4.0)):
        V, dV = 3 + 2 * time, 2.0
        frame = tnb(s)
        kappa = A / C ** 2
        tau = -(tnb(s + h)[2] - tnb(s - h)[2]) / (2 * h) @ frame[1]  # B' = -τ N
        fs = el._state_at(system, drive, time, s)
        darboux = np.array([tau, 0.0, kappa])
        assert np.allclose(fs.v0, [V, 0, 0], rtol=0, atol=1e-9)
        assert np.allclose(fs.a0, [dV, V ** 2 * kappa, 0], rtol=0, atol=1e-7)
        assert np.allclose(fs.w, V * darboux, rtol=0, atol=1e-8)
        assert np.allclose(fs.dw, dV * darboux, rtol=0, atol=1e-7)
        assert np.allclose(fs.nu, frame[:, 1], rtol=0, atol=1e-9)
        # the vectorised frame_motion gives the same rows
        fr = el.frames(drive, np.array([s, s]), system.mdl.l)
        v0, a0, w, dw = el.frame_motion(fr, np.array([V, 2 * V]), np.array([dV, 0.0]))
        assert np.allclose(v0, [[V, 0, 0], [2 * V, 0, 0]], rtol=0, atol=1e-9)
        assert np.allclose(a0, [[dV, V ** 2 * kappa, 0], [0, 4 * V ** 2 * kappa, 0]], rtol=0, atol=1e-7)
        assert np.allclose(w, [V * darboux, 2 * V * darboux], rtol=0, atol=1e-8)
        assert np.allclose(dw, [dV * darboux, 0 * darboux], rtol=0, atol=1e-7)
