"""The grain's vectors that its Python reference (:mod:`symmech.grain.flight`, :mod:`symmech.grain.sliding`,
:mod:`symmech.grain.motion`) and its compiled engine (:mod:`symmech.grain.motion_engine.layouts`) share, declared
once (:mod:`symmech.core.layout`): a flight's rotation state, a sliding contact's state and a trajectory row.
No numba, nothing of either engine here."""
from __future__ import annotations

from symmech.core.layout import Field, Layout

# The vectors the integrators advance: a flight's torque-free rotation, and a sliding contact's state.
ROTATION = Layout("GrainRotation", (
    Field("q", "1", "orientation quaternion", (4,)),
    Field("w", "rad/s", "angular velocity in body axes", (3,)),
))
SLIDE_STATE = Layout("GrainSlideState", (
    Field("r", "m", "tangential centre position in KXYZ", (2,)),
    Field("v", "m/s", "tangential centre velocity in KXYZ", (2,)),
    Field("w", "rad/s", "angular velocity in KXYZ", (3,)),
    Field("q", "1", "orientation quaternion", (4,)),
    Field("work", "J/kg", "work of the surface on the grain since the phase's start, per unit mass"),
    Field("loss", "J/kg", "energy dissipated by friction since the phase's start, per unit mass"),
))
# One trajectory row (the columns of motion.TRAJECTORY_COLUMNS), as both engines return them.
TRAJECTORY_ROW = Layout("GrainTrajectoryRow", (
    Field("t", "s", "time"),
    Field("r", "m", "centre position in KXYZ", (3,)),
    Field("v", "m/s", "centre velocity in KXYZ", (3,)),
    Field("q", "1", "orientation quaternion (unit)", (4,)),
    Field("w", "rad/s", "angular velocity in KXYZ", (3,)),
    Field("regime", "1", "regime code: FLIGHT, IMPACT or SLIDING"),
))
T_AT = TRAJECTORY_ROW.slots
