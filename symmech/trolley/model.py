"""Kinematics and reactions of the rigid trolley along a track (numpy + generated code).

Arrays have a leading axis of n samples along the track. Frames are passive
(fixed -> body components). The default is the physically consistent model:

* case 1: body frame = moving frame Ox1x2x3 (tangent x1; twist or Frenet);
* case 2: body frame Ox̄1x̄2x̄3 turned by the exact rotation Λ* that puts x̄1 on
  the chord O -> A (local curvature between the axles);
* ω = V0 Ω, ω̇ = V̇0 Ω + V0² Ω' with Ω the angular velocity per unit length,
  including the rate of Λ* itself in case 2.

:func:`paper_case` reproduces the paper's example with its own conventions
(see docs/scenes-trolley.md, "paper conventions").
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from symmech.core.scene import SymmechError
from symmech.generated import trolley_dynamics as dyn
from symmech.generated import trolley_frame as frm
from symmech.generated import trolley_printed as printed

# Tangent closer than this to vertical makes the aircraft angles singular.
GIMBAL_MARGIN = 1e-9
# Frenet frame: curvature below this [1/m] counts as zero.
KAPPA_MIN = 1e-9


@dataclass(frozen=True)
class Body:
    """Rigid body on the trolley: mass [kg], centre of mass r [m] (body frame),
    central inertia [I11, I22, I33, I12, I23, I13] [kg m²], axle distance l [m],
    half gauge ah [m], gravitational acceleration g0 [m/s²] (0 without gravity)."""

    m: float
    r: tuple
    inertia: tuple
    l: float
    ah: float
    g0: float


@dataclass
class Frame:
    """Body frame along s: ``lam`` (n, 3, 3) fixed -> body; ``e``, ``de`` (n, 3) the
    direction of V0 in body components and its s-derivative [1/m]; ``W``, ``dW`` (n, 3)
    angular velocity per unit length [rad/m] and its s-derivative [rad/m²]."""

    lam: np.ndarray
    e: np.ndarray
    de: np.ndarray
    W: np.ndarray
    dW: np.ndarray
    info: dict = field(default_factory=dict)


def _cols(v):
    """Split (..., 3) into three (...) arrays for the generated functions."""
    return [v[..., 0], v[..., 1], v[..., 2]]


def _mv(m, v):
    """Matrix (..., 3, 3) times vector (..., 3)."""
    return np.einsum("...ij,...j->...i", m, v)


def _first_bad(s, bad):
    return float(np.asarray(s)[np.argmax(bad)])


def moving_frame(track, s, mode: str) -> Frame:
    """Case 1 frame: x1 along the tangent; ``mode`` "twist" (aircraft angles with the
    scene's θ1(s)) or "frenet" (x2 along the principal normal)."""
    s = np.asarray(s, dtype=float)
    X = track.derivatives(s, 4 if mode == "frenet" else 3)
    t = X[1] / np.linalg.norm(X[1], axis=-1, keepdims=True)
    e = np.zeros(s.shape + (3,))
    e[..., 0] = 1.0
    if mode == "frenet":
        # Remove the tangential part a spline's near-unit speed leaves in X0''.
        normal = X[2] - (X[2] * t).sum(-1, keepdims=True) * t
        cross = np.cross(t, normal)
        kappa = np.linalg.norm(normal, axis=-1)
        bad = kappa < KAPPA_MIN
        if np.any(bad):
            raise SymmechError(f"Frenet frame undefined: track curvature is zero at s = {_first_bad(s, bad):.6g} m "
                               "(straight piece or inflection); use frame = \"twist\"")
        n = normal / kappa[..., None]
        tau = (cross * X[3]).sum(-1) / kappa**2
        if s.ndim == 1 and len(s) > 1:
            # Between close samples the normal turns by at most ~ |Δs| sqrt(κ² + ϰ²); a sign
            # flip beyond that is an inflection point, where κ passes through zero.
            rate = np.hypot(kappa, tau)
            turn = np.abs(np.diff(s)) * np.maximum(rate[1:], rate[:-1])
            flip = ((n[1:] * n[:-1]).sum(-1) < 0) & (turn < 1.0)
        else:
            flip = np.zeros(0, bool)
        if np.any(flip):
            raise SymmechError(f"Frenet frame undefined: the principal normal flips between s = "
                               f"{_first_bad(s[:-1], flip):.6g} m and the next sample (inflection point); "
                               "use frame = \"twist\"")
        lam = np.stack([t, n, np.cross(t, n)], axis=-2)
        dkappa = (normal * X[3]).sum(-1) / kappa
        dtau = (cross * X[4]).sum(-1) / kappa**2 - 2 * tau * dkappa / kappa
        zero = np.zeros_like(kappa)
        W = np.stack([tau, zero, kappa], axis=-1)
        dW = np.stack([dtau, zero, dkappa], axis=-1)
        return Frame(lam, e, np.zeros_like(e), W, dW)
    bad = np.abs(t[..., 1]) > 1 - GIMBAL_MARGIN
    if np.any(bad):
        raise SymmechError(f"track tangent is vertical at s = {_first_bad(s, bad):.6g} m: the aircraft angles "
                           "θ2, θ3 are singular there; use frame = \"frenet\"")
    ang = frm.angles_from_tangent(*_cols(t), *_cols(X[2]), *_cols(X[3]))
    th1, dth1, ddth1 = track.twist(s)
    th = (th1, ang[..., 0], ang[..., 1])
    dth = (dth1, ang[..., 2], ang[..., 3])
    ddth = (ddth1, ang[..., 4], ang[..., 5])
    return Frame(frm.Lambda(*th), e, np.zeros_like(e), frm.omega_per_length(*th, *dth),
                 frm.omega_per_length_rate(*th, *dth, *ddth))


def chord_point(track, s, l: float) -> np.ndarray:
    """s_A with |X0(s_A) - X0(s)| = l, s_A > s (the front axle on the midline) [m]."""
    s = np.asarray(s, dtype=float)
    x0 = track.derivatives(s, 0)[0]
    sa = s + l  # the chord is never longer than the arc, so the root is at or beyond s + l
    for _ in range(60):
        xa, ta = track.derivatives(sa, 1)
        d = xa - x0
        f = (d * d).sum(-1) - l * l
        slope = 2 * (d * ta).sum(-1)
        ok = slope > 1e-3 * l
        step = np.where(ok, -f / np.where(ok, slope, 1.0), l)
        sa = sa + np.clip(step, -0.5 * l, l)
        if np.all(np.abs(f) <= 1e-12 * l * l) and np.all(ok):
            break
    xa = track.derivatives(sa, 0)[0]
    err = np.abs(np.linalg.norm(xa - x0, axis=-1) - l)
    if not np.all(err <= 1e-9 * l) or not np.all(sa > s):
        bad = ~(err <= 1e-9 * l) | ~(sa > s)
        raise SymmechError(f"no front-axle point A at chord distance l = {l:g} m from s = {_first_bad(s, bad):.6g} m "
                           "(the track curls back within the axle distance)")
    return sa


def chord_rotation(track, s, l: float, mode: str):
    """Λ* (n, 3, 3) turning x1 onto the chord, the chord ΔR̄ (n, 3) and the moving frame."""
    base = moving_frame(track, s, mode)
    sa = chord_point(track, s, l)
    chord = track.derivatives(sa, 0)[0] - track.derivatives(s, 0)[0]
    rho = _mv(base.lam, chord) / l
    if np.any(rho[..., 0] <= 0):
        raise SymmechError(f"the chord O -> A points backwards at s = {_first_bad(s, rho[..., 0] <= 0):.6g} m")
    return frm.chord_rotation(*_cols(rho)), chord, base


def _stencil(fun, s, h, order: int):
    """First and second s-derivatives of the matrix function ``fun`` (n, 3, 3) by central
    differences of ``order`` 2 or 4; ``h`` is a step [m], scalar or of the shape of s."""
    hm = np.asarray(h, dtype=float)[..., None, None]
    if order == 2:
        fp, fm, f0 = fun(s + h), fun(s - h), fun(s)
        return (fp - fm) / (2 * hm), (fp - 2 * f0 + fm) / hm**2
    f2p, fp, f0, fm, f2m = (fun(s + k * h) for k in (2, 1, 0, -1, -2))
    d1 = (-f2p + 8 * fp - 8 * fm + f2m) / (12 * hm)
    d2 = (-f2p + 16 * fp - 30 * f0 + 16 * fm - f2m) / (12 * hm**2)
    return d1, d2


def _vee(m):
    """Vector of the skew part of m: vee(skew(v)) = v."""
    return 0.5 * np.stack([m[..., 2, 1] - m[..., 1, 2], m[..., 0, 2] - m[..., 2, 0], m[..., 1, 0] - m[..., 0, 1]], -1)


def local_curvature_frame(track, s, l: float, mode: str, fd_order: int = 4, fd_step: float = 1e-3,
                          derivatives=None) -> Frame:
    """Case 2 frame (physically consistent): Λ̄ = Λ* Λ with the exact chord rotation Λ*.

    Λ*' and Λ*'' (s-derivatives) come from central differences of order ``fd_order``
    with step ``fd_step`` [m], or from ``derivatives(s, s_A) -> (Λ*', Λ*'')`` when
    given; the body's angular velocity per unit length is Ω̄ = Λ* Ω + vee(-Λ*' Λ*ᵀ).
    """
    s = np.asarray(s, dtype=float)
    lstar, chord, base = chord_rotation(track, s, l, mode)
    if derivatives is None:
        d1, d2 = _stencil(lambda x: chord_rotation(track, x, l, mode)[0], s, fd_step, fd_order)
    else:
        d1, d2 = derivatives(s, chord_point(track, s, l))
    lt = np.swapaxes(lstar, -1, -2)
    w_rel = _vee(-d1 @ lt)
    dw_rel = _vee(-(d2 @ lt + d1 @ np.swapaxes(d1, -1, -2)))
    W = _mv(lstar, base.W) + w_rel
    dW = _mv(d1, base.W) + _mv(lstar, base.dW) + dw_rel
    info = {"psi": np.arccos(np.clip(lstar[..., 0, 0], -1, 1)), "chord": chord, "base": base}
    return Frame(lstar @ base.lam, lstar[..., :, 0], d1[..., :, 0], W, dW, info)


def small_angle_check(base: Frame, chord: np.ndarray, l: float) -> np.ndarray:
    """Orthogonality defect max|Λ̄ Λ̄ᵀ - E| of the first-order Λ̄ (13) with Δθ from (14), shape (n,).

    The aircraft angles are read off the moving frame Λ; the defect is O(Δθ²) and
    says when the small-angle correction is out of its range. Returns (defect, Δθ).
    """
    lam = base.lam
    th = (np.arctan2(-lam[..., 2, 1], lam[..., 1, 1]), np.arctan2(-lam[..., 0, 2], lam[..., 0, 0]),
          np.arcsin(np.clip(lam[..., 0, 1], -1, 1)))
    coef = frm.chord_coefficients(*th, *_cols(chord))
    rhs = np.stack([l - coef[..., 0, 0], -coef[..., 1, 0], -coef[..., 2, 0]], axis=-1)
    # (14) is rank-deficient when the chord has no x3 component (l21 = l30 = 0 and the
    # roll about the chord is free): take the minimum-norm least-squares Δθ.
    dtheta = (np.linalg.pinv(coef[..., 1:], rcond=1e-10) @ rhs[..., None])[..., 0]
    bar = frm.Lambda_bar_linear(*th, *_cols(dtheta))
    return np.abs(bar @ np.swapaxes(bar, -1, -2) - np.eye(3)).max(axis=(-1, -2)), dtheta


def point_coefficients(frame: Frame, body: Body):
    """α, β (n, 3) of the centre of mass: V = V0 α, a = V̇0 α + V0² β [1, 1/m]."""
    coef = dyn.point_coefficients(*_cols(frame.e), *_cols(frame.de), *_cols(frame.W), *_cols(frame.dW), *body.r)
    return coef[..., :3], coef[..., 3:]


def body_motion(frame: Frame, V0, dV0, body: Body) -> dict:
    """V, a (n, 3) of the centre of mass, ω, ω̇, reactions P (n, 6) and overloads (n, 3) [g].

    V0 [m/s] and dV0 [m/s²] have shape (n,).
    """
    V0, dV0 = np.asarray(V0, dtype=float), np.asarray(dV0, dtype=float)
    alpha, beta = point_coefficients(frame, body)
    V = V0[..., None] * alpha
    a = dV0[..., None] * alpha + (V0**2)[..., None] * beta
    w = V0[..., None] * frame.W
    dw = dV0[..., None] * frame.W + (V0**2)[..., None] * frame.dW
    return _dynamics(V, a, w, dw, frame.lam, body)


def _dynamics(V, a, w, dw, lam, body: Body) -> dict:
    nu = lam[..., :, 1]
    common = (body.m, *body.r, *body.inertia, *_cols(a), *_cols(w), *_cols(dw))
    if body.g0 > 0:
        P = dyn.reactions(*common, *_cols(nu), body.g0, body.l, body.ah)
    else:
        P = dyn.reactions_no_gravity(*common, body.l, body.ah)
    g_ref = body.g0 if body.g0 > 0 else 9.80665
    overload = (a + body.g0 * nu) / g_ref
    return {"V": V, "a": a, "omega": w, "omega_dot": dw, "P": P, "overload": overload, "lam": lam}


def paper_lstar(track, s, l: float, mode: str):
    """Λ* of the helix example as the paper builds it: ξ = t × ρ in fixed-frame
    components, not normalized (|ξ| = sin Ψ), in the printed Rodrigues matrix."""
    base = moving_frame(track, s, mode)
    sa = chord_point(track, s, l)
    rho = (track.derivatives(sa, 0)[0] - track.derivatives(s, 0)[0]) / l
    t = base.lam[..., 0, :]
    psi = np.arccos(np.clip((t * rho).sum(-1), -1, 1))
    xi = np.cross(t, rho)
    return printed.rodrigues(psi, *_cols(xi)), base


def paper_case(track, s, V0, dV0, body: Body, mode: str, local_curvature: bool,
               derivative: str = "backward", dlstar=None) -> dict:
    """The paper's example computation (Tables 1, 2), on a time grid (s, V0, dV0 of shape (n,)).

    Conventions (physically inconsistent ones marked *):
    * ω = Ω, the angular velocity per unit length, used as rad/s (no factor V0), and
      ω̇ = Ω' V0 (zero on the helix);
    * a0 = V̇0 + ω × V0 (so the normal acceleration is κ V0, not κ V0²);
    * case 2: Λ* from :func:`paper_lstar`; V0* = Λ* V0, ω* = Λ* ω,
      V̇0* = Λ̇* V0 + Λ* V̇0, ω̇* = Λ̇* ω + Λ* ω̇ with Λ̇* = dΛ*/ds |V0|;
    * dΛ*/ds by a backward difference between successive grid points (``derivative``
      = "backward"), or "central2"/"central4" with step |V0| Δt, or given as ``dlstar``.
    """
    base = moving_frame(track, s, mode)
    V0, dV0 = np.asarray(V0, dtype=float), np.asarray(dV0, dtype=float)
    W, dW = base.W, base.dW * V0[..., None]
    vel = np.zeros(V0.shape + (3,))
    vel[..., 0] = V0
    dvel = np.zeros_like(vel)
    dvel[..., 0] = dV0
    lam = base.lam
    if local_curvature:
        lstar, _ = paper_lstar(track, s, body.l, mode)
        if dlstar is None:
            dlstar = paper_lstar_derivative(track, s, body.l, mode, lstar, derivative)
        rate = dlstar * V0[..., None, None]
        vel, dvel = _mv(lstar, vel), _mv(rate, vel) + _mv(lstar, dvel)
        W, dW = _mv(lstar, W), _mv(rate, W) + _mv(lstar, dW)
        lam = lstar @ lam
    r = np.asarray(body.r, dtype=float)
    V = vel + np.cross(W, r)
    a = dvel + np.cross(W, vel) + np.cross(dW, r) + np.cross(W, np.cross(W, r))
    return _dynamics(V, a, W, dW, lam, body)


def paper_lstar_derivative(track, s, l, mode, lstar, method: str):
    """dΛ*/ds on the grid s (n,) by ``method``: "backward" (the paper's), "central2", "central4"."""
    fun = lambda x: paper_lstar(track, x, l, mode)[0]  # noqa: E731
    ds = np.diff(s)
    if method == "backward":
        out = np.empty_like(lstar)
        out[1:] = (lstar[1:] - lstar[:-1]) / np.where(ds > 0, ds, 1.0)[:, None, None]
        out[1:][ds <= 0] = 0.0
        out[0] = out[1] if len(s) > 1 else 0.0
        return out
    h = np.concatenate([ds[:1], ds]) if len(s) > 1 else np.array([1e-3])
    h = np.maximum(h, 1e-6 * l)
    order = {"central2": 2, "central4": 4}[method]
    return _stencil(fun, s, h, order)[0]
