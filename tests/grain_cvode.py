"""FMPy's CVode driver (tests/fmpy_cvode.py) on the grain's flight as the Model Exchange FMU poses it, without the
FMU: the generated numpy ``grain_motion``'s rates in the FMU's states (the centre relative to the vibrating
surface, quaternion, body rates), its gap as the event indicator and its impact map at each zero where the contact
point approaches (a bounce); CVode reset after each, as FMPy resets it. It tells the FMU's error in flight apart
from CVode's (tests/test_export_grain.py, benchmarks/grain_me_error.py)."""
from __future__ import annotations

from collections.abc import Callable

import numpy as np

from fmpy_cvode import Driven
from symmech.export.grain import nominals
from symmech.generated import grain_motion as gm


class Flight:
    """A prepared grain scene's (``symmech.grain.motion_scene.GrainScene``) flight parameters ``p`` (grain_motion's
    PARAMS), impact law (mass [kg], e_n, e_t, mu) and the FMU's state nominals."""

    def __init__(self, sc):
        vib, model = sc.model.vibration, sc.model
        self.p = np.array([*model.g_k, vib.amplitude, vib.omega, vib.phase, *vib.direction, *model.inertia,
                           *model.axes])
        self.law = (model.mass, model.law.e_n, model.law.e_t, model.law.mu)
        self.nominals = np.array(nominals(sc))

    def rate(self, t: float, y: np.ndarray) -> np.ndarray:
        """y' (13,) at the relative state ``y`` (13,) and time ``t`` [s]."""
        return gm.rhs(t, y, self.p)

    def gap(self, t: float, y: np.ndarray) -> np.ndarray:
        """The event indicator (1,): the gap [m]."""
        return np.ravel(gm.event_values(t, *y, *self.p))

    def bounce(self, y: np.ndarray) -> np.ndarray | None:
        """The relative state after the impact map at the relative state ``y`` on the surface, None where the
        contact point does not approach (the gap rising through zero)."""
        args = (*y, *self.p[9:], self.law[0])
        contact = gm.impact_contact(*args)
        if contact[11] >= 0:
            return None
        plastic = gm.plastic_impulse(*contact[:12])
        impulse = gm.coulomb_impulse(plastic[0], *plastic[1:4], contact[11], *self.law[1:])
        return np.asarray(gm.impact_state(*args, *impulse), float)

    def impacts(self, t0: float, y0: np.ndarray, count: int, rtol: float, interval: float) -> np.ndarray:
        """The times [s] of the first ``count`` bounces of CVode's run from the relative state ``y0`` at ``t0`` [s],
        stepped as simulate_fmu steps the FMU with ``output_interval`` and max step ``interval`` [s] (stop_time / 50
        both in the tests)."""
        return bounces(Driven(self.rate, y0, self.nominals, t0, rtol, interval, events=self.gap, nz=1,
                              max_steps=100_000), count, interval, lambda t, y: self.bounce(y))


def bounces(run: Driven, count: int, interval: float, update: Callable) -> np.ndarray:
    """The times [s] of the first ``count`` events of ``run`` at which ``update(t, y)`` returns a new state (a
    bounce; None: no event, the state kept), CVode called towards each next multiple of ``interval`` [s] (the
    output grid: it sets CVode's first step after a reset) and reset after every event."""
    times, t = [], run.state["t"]
    while len(times) < count:
        event, t = run.step(t, (np.floor(t / interval * (1 + 1e-12)) + 1) * interval)
        if event:
            after = update(t, run.state["y"])
            if after is not None:
                times.append(t)
                run.state["y"] = after
            run.reset(t)
    return np.array(times)
