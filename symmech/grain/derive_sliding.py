"""Layer 1: the sliding regime of the grain on its vibrating plane, in the flight's state variables.

The model is :mod:`symmech.grain.sliding`'s (its docstring: normal force n, driving force f, contact offset R,
slip s, the carried contact point's slip acceleration c, the mobility M and B = (E - [R]x M [R]x)_tt), written
here over the 13 states of the flight (``grain_motion``: centre position and velocity in KXYZ, quaternion,
body-axis rates) so that an exported model keeps one state vector through flight, slip and stick: on the plane
z and v_z hold still (z' = v_z' = 0), v_t' = f + phi, q' = q (x) (0, w)/2 and the body rates w' = Q^T M (R x
(phi, n)) (the time derivative of Q^T w_K is Q^T w_K': the spin keeps its own axis). The regime's events are
functions here too: the slip speed along a reference direction falling to v_stop, the stick force reaching the
friction cone, the normal force reaching zero (lift-off); and the friction impulse that sets the slip to a
target (zero: the contact sticks; 2 v_stop along the slip direction: it slips on); and the landing's last step, the
state put to rest on the plane after its plastic normal impulse (the centre at the support height, v_z zero and,
turning about the normal only, the tilting spin dropped).

The mobility M blends the two bodies of the Python model by the parameter ``roll`` (1: a sphere, M = m I1^-1 E,
rolling about any axis; 0: any other ellipsoid, M = m e_z e_z^T / I_zz, turning about the normal only); the
Python model's point mass (rotation off, M = 0) is not derived: the export refuses that effect already. Nothing is
inverted but the 2 x 2 B, by its adjugate.
"""
from __future__ import annotations

import sympy as sp

from symmech.core import kinematics as kin
from symmech.core.derivation import ModuleSpec, NamedMatrix, args_of
from symmech.grain import derive_motion as dm

ROLE = "derivation"  # found by symmech.core.discovery

mu_s = sp.Symbol("mu_s", nonnegative=True)
roll = sp.Symbol("roll", nonnegative=True)
v_stop = sp.Symbol("v_stop", positive=True)
ref0, ref1 = sp.symbols("ref0 ref1", real=True)
target0, target1 = sp.symbols("target0 target1", real=True)

_TIME = [(dm.t, "time", "s")]
_BODY = [(dm.m, "grain mass", "kg"), (roll, "1: a sphere, rolling about any axis; 0: turning about the normal "
                                             "only", "1")]
_FRICTION = [(mu_s, "sliding friction coefficient", "1")]
_EVENT = [(v_stop, "slip speed at which a slip stops", "m/s"),
          (ref0, "reference slip direction, X component (unit vector)", "1"),
          (ref1, "reference slip direction, Y component (unit vector)", "1")]
_TARGET = [(target0, "slip after the impulse, X component", "m/s"),
           (target1, "slip after the impulse, Y component", "m/s")]
# what every function reads: time, the flight's state, gravity, vibration, inertia, semi-axes, mass and roll
_ARGS = _TIME + dm.STATE_ARGS + dm.GRAVITY_ARGS + dm.VIBRATION_ARGS + dm.INERTIA_ARGS + dm.AXES_ARGS + _BODY


class Contact:
    """The sliding contact at the symbolic state: Q (3, 3), R (3,) [m] and w_K (3,) [rad/s] in KXYZ, the
    mobility M (3, 3) [1/m^2], the slip s (2,) [m/s], c (2,) [m/s^2], f (2,) and n [m/s^2], B (2, 2)."""

    def __init__(self):
        norm = sp.sqrt(dm.q0**2 + dm.q1**2 + dm.q2**2 + dm.q3**2)
        self.Q = dm.quaternion_matrix().subs({q: q / norm for q in (dm.q0, dm.q1, dm.q2, dm.q3)}, simultaneous=True)
        self.R = self.Q * dm.contact_offset_body().subs(dict(zip((dm.n1, dm.n2, dm.n3), self.Q.row(2))))
        self.w = self.Q * sp.Matrix([dm.w1, dm.w2, dm.w3])
        i_zz = sum(inertia * self.Q[2, i] ** 2 for i, inertia in enumerate((dm.I1, dm.I2, dm.I3)))
        self.M = roll * dm.m / dm.I1 * sp.eye(3) + (1 - roll) * sp.diag(0, 0, dm.m / i_zz)
        acc = dm.surface_displacement().diff(dm.t, 2)
        self.n = acc[2] - dm.gZ
        self.f = sp.Matrix([dm.gX - acc[0], dm.gY - acc[1]])
        self.s = (sp.Matrix([dm.vx, dm.vy, dm.vz]) + self.w.cross(self.R))[:2, 0]
        # the contact point turns with the spin about the normal: R' = w_z e_z x R, c = (w x R')_t
        self.c = self.w.cross(sp.Matrix([-self.w[2] * self.R[1], self.w[2] * self.R[0], 0]))[:2, 0]
        Rx = kin.skew(self.R, kin.SYMPY)
        self.B = (sp.eye(3) - Rx * self.M * Rx)[:2, :2]

    def solve_B(self, rhs: sp.Matrix) -> sp.Matrix:
        """B^-1 rhs (2,) by the adjugate (written out: sympy's det and adjugate simplify as they go)."""
        (b00, b01), (b10, b11) = self.B.tolist()
        return sp.Matrix([b11 * rhs[0] - b01 * rhs[1], b00 * rhs[1] - b10 * rhs[0]]) / (b00 * b11 - b01 * b10)

    def stick_force(self) -> sp.Matrix:
        """phi (2,) [m/s^2] holding the slip at zero: -B^-1 (f + c)."""
        return -self.solve_B(self.f + self.c)

    def slip_force(self) -> sp.Matrix:
        """phi (2,) [m/s^2] of a slip: -mu n s / |s|."""
        return -mu_s * self.n * self.s / sp.sqrt(self.s.dot(self.s))

    def rates(self, phi: sp.Matrix) -> sp.Matrix:
        """The 13 state rates on the plane under the friction force phi (2,) per unit mass."""
        torque = self.R.cross(sp.Matrix([phi[0], phi[1], self.n]))
        return sp.Matrix([dm.vx, dm.vy, 0, *(self.f + phi), 0, *dm.quaternion_rate(), *(self.Q.T * self.M * torque)])

    def impulse(self) -> sp.Matrix:
        """The state (13,) after the friction impulse that sets the slip to (target0, target1)."""
        dphi = self.solve_B(sp.Matrix([target0, target1]) - self.s)
        dw = self.Q.T * self.M * self.R.cross(sp.Matrix([dphi[0], dphi[1], 0]))
        state = [a for a, _, _ in dm.STATE_ARGS]
        return sp.Matrix([*state[:3], state[3] + dphi[0], state[4] + dphi[1], *state[5:10],
                          *(sp.Matrix(state[10:]) + dw)])

    def rest_on_plane(self) -> sp.Matrix:
        """The state (13,) of the grain put on the plane: the centre at the support height |D n'| (the gap
        zero), v_z = 0 and the spin in KXYZ kept about the normal only (roll = 0) or whole (roll = 1)."""
        state = [a for a, _, _ in dm.STATE_ARGS]
        height = dm.support_distance()[0].subs(dict(zip((dm.n1, dm.n2, dm.n3), self.Q.row(2))))
        spin = self.Q.T * sp.diag(roll, roll, 1) * self.w
        return sp.Matrix([*state[:2], height, *state[3:5], 0, *state[6:10], *spin])


def module_specs() -> list[ModuleSpec]:
    k = Contact()
    stick = k.stick_force()
    args = args_of(_ARGS)
    functions = [
        NamedMatrix("normal_force", sp.Matrix([k.n]), args_of(_TIME + dm.GRAVITY_ARGS + dm.VIBRATION_ARGS),
                    "normal force per unit mass on a grain held on the plane (lift-off where it reaches zero)",
                    "m/s^2"),
        NamedMatrix("slip", k.s, args, "slip velocity of the contact point, v_t + (w x R)_t", "m/s"),
        NamedMatrix("stick_force", stick, args, "friction force per unit mass holding the slip at zero",
                    "m/s^2"),
        NamedMatrix("slip_direction", -stick / sp.sqrt(stick.dot(stick)), args,
                    "direction in which a zero slip starts, B^-1 (f + c) / |B^-1 (f + c)|", "1"),
        NamedMatrix("slip_rate", k.rates(k.slip_force()), args_of(_ARGS + _FRICTION),
                    "state rates of a slip on the plane", "state unit / s"),
        NamedMatrix("stick_rate", k.rates(stick), args, "state rates of a stick (rolling without slip)",
                    "state unit / s"),
        NamedMatrix("slip_events", sp.Matrix([k.s.dot(sp.Matrix([ref0, ref1])) - v_stop, k.n]),
                    args_of(_ARGS + _EVENT), "event indicators of a slip: the slip along ref minus v_stop "
                    "(the slip stops where it falls through zero), the normal force (lift-off)", "m/s, m/s^2"),
        NamedMatrix("stick_events", sp.Matrix([mu_s * k.n - sp.sqrt(stick.dot(stick)), k.n]),
                    args_of(_ARGS + _FRICTION), "event indicators of a stick: the friction cone's margin mu n - "
                    "|phi| (a slip starts where it falls through zero), the normal force (lift-off)", "m/s^2"),
        NamedMatrix("friction_impulse", k.impulse(), args_of(_ARGS + _TARGET),
                    "state after the friction impulse that sets the slip to the target", "m, m/s, 1, rad/s"),
        NamedMatrix("rest_on_plane", k.rest_on_plane(), args_of(dm.STATE_ARGS + dm.AXES_ARGS + [_BODY[1]]),
                    "state of the grain put on the plane (a landing after its plastic normal impulse): centre at "
                    "the support height, v_z zero, the tilting spin dropped unless it rolls", "m, m/s, 1, rad/s"),
    ]
    return [ModuleSpec("grain_sliding", "Grain sliding: slip and stick on the vibrating plane, their events and "
                       "the friction impulse, over the flight's state.",
                       "symmech.grain.derive_sliding (the sliding model of symmech.grain.sliding)", functions)]
