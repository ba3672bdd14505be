"""FMPy's own CVode driver (``fmpy.sundials.CVodeSolver``) on equations given in Python, stepped as ``simulate_fmu``
steps a Model Exchange FMU: BDF with a dense Newton solve (its matrix by difference quotients unless a Jacobian is
handed), atol = rtol x each state's nominal, max step a fiftieth of the run, one ``CVode`` call (CV_NORMAL,
interpolated) per output time, the event indicators' zeros located by CVode, reset (order 1) after each event.

It runs the same integrator on the native equations (no FMU), so an FMU's ME run can be told apart from the
integrator's own error: :func:`cvode` on a linear y' = A y (tests/test_export_fmu.py, benchmarks/me_error.py,
benchmarks/modal_states.py), :func:`solver` on any rates and event indicators (benchmarks/grain_me_error.py)."""
from __future__ import annotations

from ctypes import CFUNCTYPE, POINTER, byref, c_int, c_long, c_void_p
from collections.abc import Callable

import numpy as np
from fmpy.sundials import CVodeSolver
from fmpy.sundials.libraries import sundials_cvode, sundials_sunmatrixdense
from fmpy.sundials.sundials_nvector import N_Vector
from fmpy.sundials.sundials_types import sunrealtype

# CVLsJacFn(t, y, fy, J, user_data, tmp1, tmp2, tmp3) and the calls FMPy's bindings leave out
JACOBIAN = CFUNCTYPE(c_int, sunrealtype, N_Vector, N_Vector, c_void_p, c_void_p, N_Vector, N_Vector, N_Vector)
sundials_cvode.CVodeSetJacFn.argtypes = [c_void_p, JACOBIAN]
sundials_cvode.CVodeSetJacFn.restype = c_int
sundials_cvode.CVodeGetNumSteps.argtypes = [c_void_p, POINTER(c_long)]
sundials_sunmatrixdense.SUNDenseMatrix_Data.argtypes = [c_void_p]
sundials_sunmatrixdense.SUNDenseMatrix_Data.restype = POINTER(sunrealtype)
N_VGetArrayPointer = sundials_cvode.N_VGetArrayPointer
N_VGetArrayPointer.argtypes = [N_Vector]
N_VGetArrayPointer.restype = POINTER(sunrealtype)


class _NoInput:
    def apply(self, t, **kwargs):
        pass


class Driven:
    """A CVodeSolver over ``rate(t, y)`` -> (n,) with ``events(t, y)`` -> (nz,) (none when None): ``state`` holds
    the time and the state CVode last set (``state["y"]`` may be replaced between steps, then :meth:`reset`)."""

    def __init__(self, rate: Callable, y0: np.ndarray, nominals: np.ndarray, t0: float, rtol: float, max_step: float,
                 events: Callable | None = None, nz: int = 0, jacobian: Callable | None = None,
                 max_steps: int = 500):
        self.state = {"t": t0, "y": np.array(y0, float)}
        state, n = self.state, len(y0)

        def put(values):
            return lambda p, k: np.ctypeslib.as_array(p, (k,)).__setitem__(slice(None), values())

        def set_x(p, k):
            state["y"] = np.ctypeslib.as_array(p, (k,)).copy()

        self.solver = CVodeSolver(nx=n, nz=nz, get_x=put(lambda: state["y"]), set_x=set_x,
                                  get_dx=put(lambda: rate(state["t"], state["y"])),
                                  get_z=put(lambda: events(state["t"], state["y"])) if nz else (lambda p, k: None),
                                  get_nominals=put(lambda: nominals), set_time=lambda t: state.__setitem__("t", t),
                                  input=_NoInput(), startTime=t0, maxStep=max_step, relativeTolerance=rtol,
                                  maxNumSteps=max_steps)
        if jacobian is not None:
            def exact(t, y, fy, matrix, user_data, tmp1, tmp2, tmp3):
                at = np.ctypeslib.as_array(N_VGetArrayPointer(y), (n,)).copy()
                np.ctypeslib.as_array(sundials_sunmatrixdense.SUNDenseMatrix_Data(matrix), (n, n))[:] = \
                    jacobian(t, at).T  # by columns
                return 0
            self.jacobian = JACOBIAN(exact)  # held against garbage collection while CVode may call it
            assert sundials_cvode.CVodeSetJacFn(self.solver.cvode_mem, self.jacobian) == 0

    def step(self, t: float, t_next: float) -> tuple[bool, float]:
        """CVode from ``t`` towards ``t_next`` [s]: (an indicator's zero stopped it, the time reached)."""
        event, _, reached = self.solver.step(t, t_next)
        self.state["t"] = reached
        return event, reached

    def reset(self, t: float) -> None:
        """CVode restarted at ``t`` [s] from ``state["y"]`` (FMPy's after each event: order 1, nominals read)."""
        self.state["t"] = t
        self.solver.reset(t)

    def steps(self) -> int:
        count = c_long()
        sundials_cvode.CVodeGetNumSteps(self.solver.cvode_mem, byref(count))
        return count.value


def cvode(A: np.ndarray, y0: np.ndarray, nominals: np.ndarray, t: np.ndarray, rtol: float,
          max_step: float | None = None, jacobian: bool = False) -> tuple[np.ndarray, int]:
    """y (len(t), n) of y' = A y from y0 at the times t [s], and CVode's number of steps. ``max_step`` [s]:
    simulate_fmu's (t[-1] - t[0]) / 50 unless given; ``jacobian``: CVode is handed A (else it differences the
    rates, as under FMPy)."""
    run = Driven(lambda time, y: A @ y, y0, nominals, t[0], rtol,
                 (t[-1] - t[0]) / 50 if max_step is None else max_step,
                 jacobian=(lambda time, y: A) if jacobian else None)
    out = [run.state["y"].copy()]
    for k in range(1, len(t)):
        reached = t[k - 1]
        while reached < t[k] - 1e-14 * t[-1]:
            _, reached = run.step(reached, t[k])
        out.append(run.state["y"].copy())
    return np.array(out), run.steps()
