"""The compiled grain engine's vectors and codes, shared by its loop (:mod:`symmech.grain.motion_engine.loop`)
and its Python side (:mod:`symmech.grain.motion_engine.driver`): the declared layouts (:mod:`symmech.core.layout`) of
the parameter vector, the state, the carry vector, the sliding parameters, the impact, trajectory and warning
rows, the vectors its integrators advance (a flight's rotation, a sliding contact's state), and the loop's scratch
vectors (a flight's record and rotation steps, a sliding step, the sampler); the
regime, status and warning codes, and the limits both sides apply. No numba here.

The loop reads a slot through a layout's offsets, ``p[P_AT.mass]``, ``z[Z_AT.work]``: ``P_AT``, ``Z_AT`` and the others
are named tuples of integers, constants of the compiled code."""
from __future__ import annotations

import numpy as np

from symmech.numerics import dop853_tableau as dop853
from symmech.core.layout import Field, Layout
from symmech.grain import motion, sliding
from symmech.grain.vectors import ROTATION, SLIDE_STATE, TRAJECTORY_ROW  # shared with the Python reference

PARAMS = Layout("GrainParams", (
    Field("axes", "m", "semi-axes a, b, c of the ellipsoid", (3,)),
    Field("mass", "kg", "mass"),
    Field("inertia", "kg m^2", "principal moments of inertia about the body axes", (3,)),
    Field("g", "m/s^2", "gravity in the surface frame KXYZ", (3,)),
    Field("amplitude", "m", "surface vibration amplitude"),
    Field("omega", "rad/s", "surface vibration angular frequency"),
    Field("phase", "rad", "surface vibration phase at t = 0"),
    Field("direction", "1", "unit direction of the surface vibration", (3,)),
    Field("law", "1", "impact law: LAW_COULOMB or LAW_PRINTED"),
    Field("e_n", "1", "normal restitution of the Coulomb law"),
    Field("e_t", "1", "tangential restitution of the Coulomb law"),
    Field("mu_impact", "1", "friction coefficient of the Coulomb law"),
    Field("e", "1", "restitution of the printed law"),
    Field("lam", "1", "tangential factor of the printed law"),
    Field("check_printed", "1", "1: check the printed law's verdict beside the Coulomb law"),
    Field("mu", "1", "sliding friction coefficient"),
    Field("rotation", "1", "1: the grain rotates"),
    Field("tolerance", "1", "relative tolerance of the integrators and root finders"),
    Field("scan_step", "s", "time step of the contact scan"),
    Field("rest_velocity", "m/s", "approach speed below which a landing starts sliding"),
    Field("max_impacts", "", "impacts after which the run stops"),
    Field("sample_interval", "s", "time between two trajectory rows"),
    Field("period", "s", "surface vibration period (chatter and chunk lengths)"),
    Field("exact_flight", "1", "1: the flight in closed form (free_flight_nb), else the rotation by DOP853"),
))
STATE = Layout("GrainState", (
    Field("t", "s", "time"),
    Field("r", "m", "centre position in KXYZ", (3,)),
    Field("v", "m/s", "centre velocity in KXYZ", (3,)),
    Field("q", "1", "orientation quaternion (unit)", (4,)),
    Field("w", "rad/s", "angular velocity in body axes", (3,)),
))
# The loop's own state between two calls.
CARRY = Layout("GrainCarry", (
    Field("regime", "1", "regime code: FLIGHT, IMPACT or SLIDING"),
    Field("on_plane", "1", "1: the grain touches the plane at the start of a flight"),
    Field("landings", "", "landings (impacts ending in sliding)"),
    Field("idle", "", "regime changes in a row without advancing time"),
    Field("t_flight", "s", "time in flight"),
    Field("t_sliding", "s", "time sliding"),
    Field("work", "J", "work of the surface on the grain"),
    Field("impacts", "J", "kinetic energy lost in impacts"),
    Field("land_loss", "J", "kinetic energy lost in landings"),
    Field("slide_loss", "J", "energy dissipated by sliding friction"),
    Field("rows", "", "trajectory rows written"),
    Field("nimp", "", "impact rows written"),
    Field("nwarn", "", "warning rows written"),
    Field("rocking", "", "rocking contacts"),
    Field("implicit", "", "accepted Radau steps of stiff slips"),
    Field("e_start", "J", "absolute energy at the start"),
    Field("e_end", "J", "absolute energy at the end"),
))
# Parameters of one sliding phase (the sliding right-hand side's), set up at its start.
SLIDE = Layout("GrainSlide", (
    Field("g", "m/s^2", "gravity in KXYZ", (3,)),
    Field("amplitude", "m", "surface vibration amplitude"),
    Field("omega", "rad/s", "surface vibration angular frequency"),
    Field("phase", "rad", "surface vibration phase at t = 0"),
    Field("direction", "1", "unit direction of the surface vibration", (3,)),
    Field("mu", "1", "sliding friction coefficient"),
    Field("r0", "m", "contact point from the centre at the start, KXYZ", (3,)),
    Field("rb", "m", "contact point from the centre, body axes", (3,)),
    Field("sphere", "1", "1: the grain is a sphere (the contact point is fixed)"),
    Field("m", "1", "mass-normalised inverse inertia M of the contact, row by row", (9,)),
    Field("mass", "kg", "mass"),
    Field("inertia", "kg m^2", "principal moments of inertia", (3,)),
    Field("ref", "1", "unit slip direction at the start of a slip", (2,)),
    Field("v_stop", "m/s", "slip speed counted as stopped"),
    Field("event", "1", "terminal event watched: EV_NONE, EV_SLIP, EV_STICK, EV_SLIP_STIFF or EV_FAST"),
    Field("aniso", "1", "1: the contact is anisotropic (stiff slips possible)"),
    Field("v_stiff", "m/s", "slip speed below which an anisotropic slip is stiff"),
))
# One impact row of the log (the keys of ``motion.impact_record``; flags: -1 not checked, 0 no, 1 yes).
IMPACT_ROW = Layout("GrainImpact", (
    Field("t", "s", "time of the impact"),
    Field("r", "m", "centre position", (3,)),
    Field("v_before", "m/s", "centre velocity before", (3,)),
    Field("v_after", "m/s", "centre velocity after", (3,)),
    Field("w_before", "rad/s", "angular velocity before, body axes", (3,)),
    Field("w_after", "rad/s", "angular velocity after, body axes", (3,)),
    Field("impulse", "N s", "impulse on the grain", (3,)),
    Field("u_before", "m/s", "contact point velocity before", (3,)),
    Field("u_after", "m/s", "contact point velocity after", (3,)),
    Field("ke_before", "J", "kinetic energy before"),
    Field("ke_after", "J", "kinetic energy after"),
    Field("admissible", "1", "flag: the impulse is admissible"),
    Field("printed_admissible", "1", "flag: the printed law has an admissible root"),
    Field("printed_creates_energy", "1", "flag: the printed law creates energy"),
    Field("converged", "1", "flag: the printed law's solution converged"),
))
# One warning row, as the loop returns them.
WARNING_ROW = Layout("GrainWarning", (
    Field("code", "1", "warning code W_*"),
    Field("a", "", "first value of the text (a time, a residual, an energy)"),
    Field("b", "", "second value of the text"),
))
# The loop's scratch vectors, inside one call. A flight's record, set up at its start:
FLIGHT_RECORD = Layout("GrainFlight", (
    Field("t0", "s", "time at the start of the flight"),
    Field("r0", "m", "centre position at the start, KXYZ", (3,)),
    Field("v0", "m/s", "centre velocity at the start, KXYZ", (3,)),
    Field("q0", "1", "orientation quaternion at the start", (4,)),
    Field("w0", "rad/s", "angular velocity at the start, body axes", (3,)),
    Field("inertia", "kg m^2", "principal moments of inertia", (3,)),
    Field("phase", "rad", "surface vibration phase at t0, modulo 2 pi"),
    Field("rotating", "1", "1: the rotation is integrated (else the orientation stays q0)"),
    Field("t_rot", "s", "time the rotation is integrated to"),
    Field("y_rot", "1, rad/s", "rotation state at t_rot (layout GrainRotation)", (ROTATION.size,)),
    Field("failed", "1", "1: the rotation's integration failed"),
    Field("support", "m", "support height of the lowest point at the start"),
    Field("chunk_end", "s", "end of the rotation chunk under way"),
    Field("step", "s", "next step length of the rotation's DOP853"),
    Field("f", "1/s, rad/s^2", "rotation right-hand side at t_rot", (ROTATION.size,)),
    Field("in_chunk", "1", "1: a rotation chunk is under way"),
))
# One accepted step of a flight's rotation, a row of its step table (the interpolant: numerics.dop853.dop_dense_at).
ROTATION_STEP = Layout("GrainRotationStep", (
    Field("t_old", "s", "start of the step"),
    Field("t_new", "s", "end of the step"),
    Field("y_old", "1, rad/s", "rotation state at the start of the step (layout GrainRotation)", (ROTATION.size,)),
    Field("dense", "", "the step's dense-output coefficients F (INTERPOLATOR_POWER, ROTATION.size), row by row",
          (ROTATION.size * dop853.INTERPOLATOR_POWER,)),
))
# The sliding step whose interpolant the event functions read, with the phase's parameters.
SLIDE_STEP = Layout("GrainSlideStep", (
    Field("t_old", "s", "start of the step"),
    Field("h", "s", "length of the step"),
    Field("z_old", "", "sliding vector at the start of the step (layout GrainSlideState)", (SLIDE_STATE.size,)),
    Field("radau", "1", "1: a Radau IIA step (else DOP853)"),
    Field("sp", "", "the phase's sliding parameters (layout GrainSlide)", (SLIDE.size,)),
))
# Where the trajectory rows of a sliding phase stand.
SAMPLER = Layout("GrainSampler", (
    Field("next", "", "index k of the next sample time k * interval"),
    Field("interval", "s", "time between two trajectory rows"),
    Field("t_start", "s", "start of the sliding phase"),
    Field("height", "m", "centre height of the sliding grain"),
))
# Offsets by field name (P_AT.mass == 3): what the loop indexes with.
P_AT, X_AT, C_AT, S_AT, I_AT = PARAMS.slots, STATE.slots, CARRY.slots, SLIDE.slots, IMPACT_ROW.slots
T_AT, WR_AT = TRAJECTORY_ROW.slots, WARNING_ROW.slots
FL_AT, RS_AT, SS_AT, SM_AT = FLIGHT_RECORD.slots, ROTATION_STEP.slots, SLIDE_STEP.slots, SAMPLER.slots
RO_AT, Z_AT = ROTATION.slots, SLIDE_STATE.slots
N_STATE, N_SLIDE, N_FLIGHT, N_SAMPLER = STATE.size, SLIDE.size, FLIGHT_RECORD.size, SAMPLER.size  # numba: ints
N_ROTATION, N_SLIDING = ROTATION.size, SLIDE_STATE.size
ROT_WIDTH, N_SLIDE_STEP, WARNING_WIDTH = ROTATION_STEP.size, SLIDE_STEP.size, WARNING_ROW.size
LAYOUTS = (PARAMS, STATE, CARRY, SLIDE, IMPACT_ROW, TRAJECTORY_ROW, WARNING_ROW)  # symmech.core.engines: describe
LAW_COULOMB, LAW_PRINTED = 0.0, 1.0

# Integer codes are numpy scalars, not Python ints: numba types a Python int constant passed to a jitted
# function as a literal and compiles that function once more for every such value (83 instead of 61 overloads).
INT = np.int64
FLIGHT, IMPACT, SLIDING = INT(0), INT(1), INT(2)  # regime codes, as motion.REGIMES
# Status of a call.
DONE, MORE, STALLED, SLIDE_STALLED, SLIDE_RHS, SLIDE_FAIL, ROT_FAIL = (INT(k) for k in range(7))
# Warning codes (rows: code, value, value).
W_MAX_IMPACTS, W_CHATTER, W_PRINTED_ENERGY, W_PRINTED_PULLS, W_PRINTED_RESIDUAL, W_ENERGY = (
    INT(k) for k in range(1, 7))
IMPACT_WIDTH = IMPACT_ROW.size
TRAJECTORY_WIDTH = TRAJECTORY_ROW.size  # len(motion.TRAJECTORY_COLUMNS): tests/test_layouts.py

PHASES_PER_CALL = INT(2000)  # a numpy int: passed inside the loop (run_many), no literal overload of run
COLD_COMPILE_SECONDS = 80.0  # wall time of the first compile, idle machine: 78 s (benchmarks/bench_grain_compile.py)
ZENO_IMPACTS, ZENO_INTERVAL, MAX_IDLE_STEPS = motion.ZENO_IMPACTS, motion.ZENO_INTERVAL, motion.MAX_IDLE_STEPS
MAX_STALLED_EVENTS = sliding.MAX_STALLED_EVENTS
