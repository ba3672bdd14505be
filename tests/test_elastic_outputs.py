"""The per-row outputs of the elastic trolley (`outputs`, `row_terms`) on hand-made states, against the point cloud.

The body is the cloud of tests/test_elastic_energies.py (a trolley on rollers and a cantilever with a tip mass,
written out as weighted points moving to r̃ = r + φᵀ q + ½ qᵀ H q), with two massless report points added: one on
the trolley and the beam's tip. Three rows of random states on a catenary with a twist (height y_O = √(400 + s²)
in closed form) at three speeds and rates, no integration: every output is checked against sums over the points,
the roller law and the statics of the contacts. The accelerations are checked by the virtual work of the
d'Alembert forces (tests/test_elastic_residual.py), so the references need no value of the code under test."""
import dataclasses
import sys
from pathlib import Path

import numpy as np
import pytest

from symmech.generated import trolley_elastic as gen
from symmech.trolley.elastic import system as el, body as el_body, frame as el_frame, simulate as el_sim
from symmech.trolley.elastic import scene as elastic_scene

sys.path.insert(0, str(Path(__file__).parent))
from test_elastic_energies import (BEAM, G0, HALF_GAUGE, K_ROLL, L_AXLE, bending_energy, cloud,  # noqa: E402
                                   kinematics, model, resultants_of_cloud)
from test_elastic_residual import C_ROLL, elastic_forces, virtual_work  # noqa: E402
from test_trolley_elastic_kind import CATENARY  # noqa: E402
from trolley_util import prepared  # noqa: E402

pytestmark = pytest.mark.xdist_group("test_elastic_outputs")

RNG = np.random.default_rng(41)
C = gen.roller_matrix(L_AXLE, HALF_GAUGE)
TROLLEY_PROBE = (0.9, -0.4, 0.7)
PROBES = ((None, TROLLEY_PROBE), (0, 1.0))  # the trolley point, the beam's tip
# the rigid rollers' reaction system: P0 along x1 at O, B and C along x2 at x3 = ∓ah, A along x2 at x1 = l,
# then along x3 at O and at x1 = l
CONTACTS = np.array([(0, 0, 0), (0, 0, -HALF_GAUGE), (0, 0, HALF_GAUGE), (L_AXLE, 0, 0), (0, 0, 0),
                     (L_AXLE, 0, 0)], float)
DIRECTIONS = np.eye(3)[[0, 1, 1, 1, 2, 2]]


@pytest.fixture(scope="module")
def drive():
    return elastic_scene.drive_of(prepared(CATENARY), 1)


def with_probes(body, rollers):
    """The cloud with the two report points appended, massless: the trolley point (rigid fields) and the tip."""
    pts, w, phi, H = body
    N = phi.shape[1]
    p = np.array(TROLLEY_PROBE)
    phi_p, H_p = np.zeros((1, N, 3)), np.zeros((1, N, N, 3))
    if rollers:
        rigid = np.moveaxis(gen.rigid_fields(*p[:, None]), -1, 1)  # (1, 11, 3)
        phi_p[:, :5] = rigid[:, :5]
        for col, (i, j) in enumerate(el_body.ROTATION_PAIRS):
            H_p[:, i, j] = H_p[:, j, i] = rigid[:, 5 + col]
    return (np.vstack([pts, p, pts[-1]]), np.r_[w, 0.0, 0.0], np.concatenate([phi, phi_p, phi[-1:]]),
            np.concatenate([H, H_p, H[-1:]]))


def rows_of(system, n=3):
    """Arc lengths, speeds, rates and states Y (n, 2N + 2) of n rows; the states far from any equilibrium."""
    N = system.N
    s = np.array([3.0, 11.0, 17.5])[:n]
    V0, dV0 = np.array([8.0, 10.5, 6.0])[:n], np.array([3.0, -2.0, 1.5])[:n]
    q = RNG.normal(size=(n, N)) * np.r_[np.full(N - 2 * BEAM.modes, 1e-2), np.full(2 * BEAM.modes, 0.1)]
    qd = RNG.normal(size=(n, N))
    Y = np.column_stack([q, qd, [1.5, 2.5, 4.0][:n], [-30.0, 20.0, 70.0][:n]])
    return s, V0, dV0, Y


def frame_states(drive, s, V0, dV0):
    fr = drive.frames(s)
    return fr, [el_frame.frame_state(fr, i, V0[i], dV0[i]) for i in range(len(s))]


def check_rows(system, body, drive, out, s, V0, dV0, Y, g0):
    """Every per-row output of ``out`` against the cloud's sums."""
    N = system.N
    w = body[1]
    _, fss = frame_states(drive, s, V0, dV0)
    g_ref = g0 if g0 > 0 else 9.80665
    for i, fs in enumerate(fss):
        q, qd, qdd = Y[i, :N], Y[i, N:2 * N], out["qdd"][i]
        cfs = dataclasses.replace(fs, nu=fs.nu * g0 / G0)  # the cloud's helpers pull by G0 along ν
        # the accelerations: the d'Alembert forces' virtual work balances the elastic forces
        forces = elastic_forces(q, qd) if system.rollers_on else beam_forces(q)
        scale = np.abs(virtual_work(body, cfs, q, qd, 0 * q)).max() + np.abs(forces).max()
        residual = virtual_work(body, cfs, q, qd, qdd) + forces
        assert np.abs(residual).max() < 1e-9 * scale
        F, M = resultants_of_cloud(body, cfs, q, qd, qdd)
        assert np.abs(out["F"][i] - F).max() < 1e-10 * np.abs(F).max()
        assert np.abs(out["M"][i] - M).max() < 1e-10 * np.abs(M).max()
        r, ud, udd = kinematics(body, q, qd, qdd)
        carried = fs.v0 + np.cross(fs.w, r)
        t2, t0, t = (0.5 * np.einsum("p,pi,pi->", w, x, x) for x in (ud, carried, carried + ud))
        d = C @ q[:5] if system.rollers_on else np.zeros(5)
        pi = bending_energy(np.r_[np.zeros(5 * (not system.rollers_on)), q]) + 0.5 * K_ROLL @ (d * d) * \
            system.rollers_on
        gravity = g0 * fs.nu @ (w @ r)
        assert out["h"][i] == pytest.approx(t2 - t0 + pi + gravity, rel=1e-11, abs=1e-11 * t)
        height = np.sqrt(400.0 + s[i] ** 2)
        assert out["E"][i] == pytest.approx(t + pi + g0 * w.sum() * height + gravity, rel=1e-11)
        # the report points, the last two of the cloud: displaced, the elastic part alone, the overload
        a = fs.a0 + np.cross(fs.dw, r) + np.cross(fs.w, np.cross(fs.w, r)) + 2 * np.cross(fs.w, ud) + udd
        assert np.abs(out["probe_displacement"][i] - (r[-2:] - body[0][-2:])).max() < 1e-13
        assert np.abs(out["probe_overload"][i] - (a[-2:] + g0 * fs.nu) / g_ref).max() < \
            1e-11 * np.abs(a[-2:]).max() / g_ref
        nb = 2 * BEAM.modes
        qb = q[-nb:]
        tip = np.einsum("ai,a->i", body[2][-1, -nb:], qb) + 0.5 * np.einsum("abi,a,b->i", body[3][-1, -nb:, -nb:],
                                                                            qb, qb)
        assert np.abs(out["probe_elastic"][i] - [np.zeros(3), tip]).max() < 1e-14
        # the rigid model's reactions carry the resultants of the undeformed body at rest relative to the frame
        F0, M0 = resultants_of_cloud(body, cfs, 0 * q, 0 * q, 0 * q)
        rigid = out["P_rigid"][i][:, None] * DIRECTIONS
        assert np.abs(rigid.sum(0) - F0).max() < 1e-9 * np.abs(F0).max()
        assert np.abs(np.cross(CONTACTS, rigid).sum(0) - M0).max() < 1e-9 * np.abs(M0).max()
        com = w @ body[0] / w.sum()
        a_com = fs.a0 + np.cross(fs.dw, com) + np.cross(fs.w, np.cross(fs.w, com))
        assert np.abs(out["overload_rigid"][i] - (a_com + g0 * fs.nu) / g_ref).max() < 1e-11 * np.abs(a_com).max()


def beam_forces(q):
    """∂Π/∂q of the beam alone (the rigid rollers' body has only the beam's coordinates)."""
    h = 1e-3
    return np.array([(bending_energy(np.r_[np.zeros(5), q + h * e]) - bending_energy(np.r_[np.zeros(5), q - h * e]))
                     / (2 * h) for e in np.eye(len(q))])


def test_outputs_on_elastic_rollers_with_dampers(drive):
    """P0 = F1, P1…P5 = -k d - c ḋ of the deflections d = C q, the moment of those forces at the displaced
    contacts; the states, speeds, times and the integrated energies handed through row by row."""
    mdl = model(damping=C_ROLL)
    system = el.System(mdl, PROBES)
    body = with_probes(cloud(mdl), True)
    s, V0, dV0, Y = rows_of(system)
    t = np.array([0.1, 0.4, 0.9])
    out = el_sim.outputs(system, drive, t, s, V0, dV0, Y)
    check_rows(system, body, drive, out, s, V0, dV0, Y, G0)
    N = system.N
    q, qd = Y[:, :N], Y[:, N:2 * N]
    d, dd = q[:, :5] @ C.T, qd[:, :5] @ C.T
    forces = -K_ROLL * d - np.asarray(C_ROLL) * dd
    assert np.abs(out["P"] - np.column_stack([out["F"][:, 0], forces])).max() < 1e-12 * np.abs(forces).max()
    assert np.abs(out["deflection"] - d).max() < 1e-16
    for i in range(3):
        rigid = np.moveaxis(gen.rigid_fields(*CONTACTS[1:].T), -1, 1)
        u = np.einsum("pai,a->pi", rigid[:, :5], q[i, :5])
        for col, (a, b) in enumerate(el_body.ROTATION_PAIRS):
            u += (0.5 if a == b else 1.0) * q[i, a] * q[i, b] * rigid[:, 5 + col]
        moment = np.cross(CONTACTS[1:] + u, forces[i][:, None] * DIRECTIONS[1:]).sum(0)
        assert np.abs(out["M_contacts"][i] - moment).max() < 1e-12 * np.abs(moment).max()
    for key, value in (("t", t), ("s", s), ("V0", V0), ("dV0", dV0), ("q", q), ("qd", qd), ("dissipated", Y[:, -2]),
                       ("work", Y[:, -1])):
        assert np.array_equal(out[key], value), key
    assert out["names"] == [*el_body.ROLLER_NAMES] + [f"beam0_p{p}_m{k}" for p in (1, 2) for k in (1, 2, 3)]
    fr, _ = frame_states(drive, s, V0, dV0)
    assert np.array_equal(out["W"], fr.W) and np.array_equal(out["dW"], fr.dW)
    assert not {"rr", "v", "acc"} & set(out)


@pytest.mark.parametrize("g0", [0.0, 0.5])
def test_outputs_on_rigid_rollers_in_weak_or_no_gravity(drive, g0):
    """Rigid rollers: the six reactions at the contacts carry F and M; no deflections, no contact moment; the
    overloads in units of g0, or of the standard gravity when g0 = 0; only the beam's part of the tip is elastic."""
    base = model(rollers=False)
    mdl = el_body.ElasticModel(base.mass, base.com, base.inertia, L_AXLE, HALF_GAUGE, g0, None, base.beams, base.effects)
    system = el.System(mdl, PROBES)
    body = with_probes(cloud(mdl), False)
    s, V0, dV0, Y = rows_of(system)
    out = el_sim.outputs(system, drive, np.arange(3.0), s, V0, dV0, Y)
    check_rows(system, body, drive, out, s, V0, dV0, Y, g0)
    for P, F, M in zip(out["P"], out["F"], out["M"]):
        forces = P[:, None] * DIRECTIONS
        assert np.abs(forces.sum(0) - F).max() < 1e-10 * np.abs(F).max()
        assert np.abs(np.cross(CONTACTS, forces).sum(0) - M).max() < 1e-10 * np.abs(M).max()
    assert np.array_equal(out["deflection"], np.zeros((3, 5)))
    assert np.array_equal(out["M_contacts"], np.zeros((3, 3)))


def test_outputs_use_the_frame_the_caller_gives(drive):
    """Case 2's frame at the same arc lengths (the chord frame, not the track's): the outputs are those of the frame
    given, and differ from case 1's."""
    mdl = model(damping=C_ROLL)
    system = el.System(mdl, PROBES)
    s, V0, dV0, Y = rows_of(system, 2)
    chord = elastic_scene.drive_of(prepared(CATENARY), 2)
    given = el_sim.outputs(system, drive, np.arange(2.0), s, V0, dV0, Y, frame=chord.frames(s))
    own = el_sim.outputs(system, chord, np.arange(2.0), s, V0, dV0, Y)
    for key in ("qdd", "F", "P", "h", "probe_overload", "P_rigid", "W"):
        assert np.array_equal(given[key], own[key]), key
    plain = el_sim.outputs(system, drive, np.arange(2.0), s, V0, dV0, Y)
    assert np.abs(plain["F"] - given["F"]).max() > 1e-4 * np.abs(plain["F"]).max()


def test_every_beam_mode_counts_as_elastic_on_a_body_without_second_order_fields(drive):
    """Rigid rollers and no stiffening: no ψ fields at all, the coordinates are the last fields; the tip's elastic
    displacement is its whole displacement, Σ N_k(1) q_k b over both planes."""
    base = model(rollers=False)
    mdl = el_body.ElasticModel(base.mass, base.com, base.inertia, L_AXLE, HALF_GAUGE, G0, None, base.beams,
                          el_body.Effects(rollers=False, stiffening=False, damping=False))
    system = el.System(mdl, PROBES)
    assert system.F == 1 + system.N
    s, V0, dV0, Y = rows_of(system, 2)
    out = el_sim.outputs(system, drive, np.arange(2.0), s, V0, dV0, Y)
    tip = np.einsum("ai,na->ni", cloud(mdl)[2][-1], Y[:, :system.N])
    assert np.abs(out["probe_elastic"][:, 1] - tip).max() < 1e-14
    assert np.abs(out["probe_displacement"][:, 1] - tip).max() < 1e-14
