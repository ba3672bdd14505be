"""FMPy's own CVode driver (``fmpy.sundials.CVodeSolver``) on a linear y' = A y, stepped as ``simulate_fmu``
steps a Model Exchange FMU without events: BDF with a dense Newton solve, atol = rtol x each state's nominal,
max step a fiftieth of the run, one ``CVode`` call (CV_NORMAL, interpolated) per output time, never reset.

It runs the same integrator on the native equations (A y from the assembled matrices, no FMU), so an FMU's ME
run can be told apart from the integrator's own error (tests/test_export_fmu.py, benchmarks/me_error.py,
benchmarks/modal_states.py)."""
from __future__ import annotations

from ctypes import CFUNCTYPE, POINTER, byref, c_int, c_long, c_void_p

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


class _NoInput:
    def apply(self, t):
        pass


def cvode(A: np.ndarray, y0: np.ndarray, nominals: np.ndarray, t: np.ndarray, rtol: float,
          max_step: float | None = None, jacobian: bool = False) -> tuple[np.ndarray, int]:
    """y (len(t), n) of y' = A y from y0 at the times t [s], and CVode's number of steps. ``max_step`` [s]:
    simulate_fmu's (t[-1] - t[0]) / 50 unless given; ``jacobian``: CVode is handed A (else it differences the
    rates, as under FMPy)."""
    state = {"y": np.array(y0, float)}
    n = len(y0)

    def put(values):
        return lambda p, k: np.ctypeslib.as_array(p, (k,)).__setitem__(slice(None), values())

    def set_x(p, k):
        state["y"] = np.ctypeslib.as_array(p, (k,)).copy()

    solver = CVodeSolver(nx=n, nz=0, get_x=put(lambda: state["y"]), set_x=set_x,
                         get_dx=put(lambda: A @ state["y"]), get_z=lambda p, k: None,
                         get_nominals=put(lambda: nominals), set_time=lambda time: None, input=_NoInput(),
                         startTime=t[0], maxStep=(t[-1] - t[0]) / 50 if max_step is None else max_step,
                         relativeTolerance=rtol)
    if jacobian:
        def exact(time, y, fy, matrix, user_data, tmp1, tmp2, tmp3):
            np.ctypeslib.as_array(sundials_sunmatrixdense.SUNDenseMatrix_Data(matrix), (n, n))[:] = A.T  # by columns
            return 0
        solver.jacobian = JACOBIAN(exact)  # held against garbage collection while CVode may call it
        assert sundials_cvode.CVodeSetJacFn(solver.cvode_mem, solver.jacobian) == 0
    out = [state["y"].copy()]
    for k in range(1, len(t)):
        reached = t[k - 1]
        while reached < t[k] - 1e-14 * t[-1]:
            _, _, reached = solver.step(reached, t[k])
        out.append(state["y"].copy())
    steps = c_long()
    sundials_cvode.CVodeGetNumSteps(solver.cvode_mem, byref(steps))
    return np.array(out), steps.value
