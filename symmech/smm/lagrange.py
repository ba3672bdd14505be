"""Independent check of the SMM: Lagrange's equations from T, Pi and Rayleigh's Phi.

Builds the exact (nonlinear) positions r(q) from rotation matrices (Rodrigues),
writes the kinetic energy, the potential energy of springs and gravity and the
dissipation function, and linearises at q = 0 by differentiation:
a = d2T/dq'dq', c = d2Pi/dq dq, b = d2Phi/dq'dq' (eqs. (1), (4), (7), (10)).
Slow on purpose (it is the textbook route); for small systems only.
"""
from __future__ import annotations

import sympy

from symmech.core import kinematics as kin
from symmech.smm.derive import SymbolicArith
from symmech.smm.model import EQUILIBRIUM, GROUND, Effects, Mechanism


def matrices(m: Mechanism, effects: Effects | None = None) -> dict[str, sympy.Matrix]:
    """a, b, c and the equilibrium residual dPi/dq (k x 1) at q = 0 by Lagrange's route."""
    eff = effects or m.effects
    ar = SymbolicArith(m)
    q = sympy.symbols(f"q0:{len(m.coordinates)}", real=True)
    qv = dict(zip(m.coordinate_names, q))
    axis = {c.name: sympy.Matrix([ar(t) for t in c.axis]) for c in m.coordinates}
    at0 = {s: 0 for s in q}

    def rot(turns):
        R = sympy.eye(3)
        for a in turns:
            R = R * kin.rodrigues(axis[a], qv[a], kin.SYMPY)
        return R

    def position(point):
        chain = m.chain(point)
        r = sympy.Matrix([ar(t) for t in chain[0].vector])
        for p in chain[1:]:
            v = sympy.Matrix([ar(t) for t in p.vector])
            for s in p.slides:
                v += qv[s] * axis[s]
            r += rot(p.turns) * v
        return r

    qm = sympy.Matrix(q)
    n = len(q)
    a = sympy.zeros(n, n)
    for b in m.bodies:
        J = position(b.com).jacobian(qm).xreplace(at0)
        a += ar(b.mass) * J.T * J
        R = rot(b.turns)
        # angular velocity omega = sum_a vee(dR/dq_a R^T) q'_a
        W = sympy.zeros(3, n)
        for i, s in enumerate(q):
            Om = (R.diff(s) * R.T).xreplace(at0)
            W[:, i] = kin.vee(Om, kin.SYMPY)
        # principal axes (columns of Rp) in equilibrium; the central inertia tensor is Rp diag(J) Rp^T
        Rp = sympy.Matrix([[ar(t) for t in ax] for ax in b.axes]).T if b.axes else sympy.eye(3)
        a += W.T * kin.rotate_tensor(Rp, sympy.diag(*[ar(t) for t in b.inertia]), kin.SYMPY) * W

    Pi = sympy.S.Zero
    unknown: dict[str, sympy.Symbol] = {}
    for s in m.springs:
        d = position(s.b) - position(s.a)
        length = sympy.sqrt(d.dot(d))
        l_eq = length.xreplace(at0)
        k = ar(s.coef)
        if s.preload == EQUILIBRIUM:
            tension = unknown.setdefault(s.name, sympy.Symbol(f"T_{s.name}"))
        elif s.preload is not None:
            tension = ar(s.preload)
        elif s.free_length is not None:
            tension = k * (l_eq - ar(s.free_length))
        else:
            tension = sympy.S.Zero
        # Pi = k/2 (l - l0)^2 with l0 = l_eq - T/k, expanded so k = 0 stays finite
        stretch = length - l_eq
        Pi += k * stretch**2 / 2 + tension * stretch
        if not eff.preload:
            Pi -= tension * stretch - tension * _first_order(stretch, q)
    for t in m.torsion_springs:
        twist = _twist(m, t, rot, axis, ar)
        Pi += ar(t.coef) * twist ** 2 / 2
        if t.preload is not None:  # the moment M0 in equilibrium does work on the twist
            moment = (unknown.setdefault(t.name, sympy.Symbol(f"M_{t.name}")) if t.preload == EQUILIBRIUM
                      else ar(t.preload))
            Pi += moment * (twist if eff.preload else _first_order(twist, q))
    grav = ar(m.gravity)
    gdir = sympy.Matrix([ar(t) for t in m.gravity_direction])
    for b in m.bodies:
        height = -(gdir.dot(position(b.com)))
        energy = ar(b.mass) * grav * height
        Pi += energy if eff.gravity else _first_order(energy, q)
    grad = sympy.Matrix([Pi.diff(s) for s in q])
    c = _hessian_of_gradient(grad, q).xreplace(at0)
    residual = grad.xreplace(at0)
    if unknown:  # eq. (5) fixes the tensions left to equilibrium: solve on independent rows
        from symmech.smm.numeric import equilibrium_tensions

        _, rows = equilibrium_tensions(m)
        sol = sympy.solve([residual[i] for i in rows], list(unknown.values()), dict=True)[0]
        c, residual = c.subs(sol), residual.subs(sol)

    Phi = sympy.S.Zero
    qd = sympy.symbols(f"qd0:{n}", real=True)
    if eff.damping:
        for d_ in m.dampers:
            d = position(d_.b) - position(d_.a)
            grad_l = sympy.Matrix([sympy.sqrt(d.dot(d)).diff(s) for s in q]).xreplace(at0)
            rate = sum(gl * v for gl, v in zip(grad_l, qd))
            Phi += ar(d_.coef) * rate**2 / 2
        for t in m.torsion_dampers:
            tw = _twist(m, t, rot, axis, ar)
            rate = sum(tw.diff(s).xreplace(at0) * v for s, v in zip(q, qd))
            Phi += ar(t.coef) * rate**2 / 2
    b = sympy.hessian(Phi, qd) if Phi != 0 else sympy.zeros(n, n)
    return {"a": a, "b": b, "c": c, "residual": residual}


def _hessian_of_gradient(grad: sympy.Matrix, q) -> sympy.Matrix:
    """sympy.hessian's matrix, d(grad_i)/dq_j, each entry the same expression, from the gradient already formed:
    sympy.hessian differentiates the whole potential again for every entry of its upper triangle."""
    n = len(q)
    h = sympy.zeros(n, n)
    for i in range(n):
        for j in range(i, n):
            h[i, j] = h[j, i] = grad[i].diff(q[j])
    return h


def _first_order(expr, q):
    """The part of expr linear in q at q = 0 (keeps the equilibrium force, drops its stiffness)."""
    at0 = {s: 0 for s in q}
    return sum((expr.diff(s).xreplace(at0) * s for s in q), sympy.S.Zero)


def _twist(m, t, rot, axis, ar):
    """Relative rotation angle (small) of body b w.r.t. body a about the element's axis."""
    Ra = rot(m.body_turns(t.a)) if t.a != GROUND else sympy.eye(3)
    Rb = rot(m.body_turns(t.b)) if t.b != GROUND else sympy.eye(3)
    return sympy.Matrix([ar(x) for x in t.axis]).dot(kin.vee(Ra.T * Rb, kin.SYMPY))
