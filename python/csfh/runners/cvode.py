"""CVODE stepping a model-exchange FMU one internal step at a time: fmpy's build of SUNDIALS
through the ctypes bindings of fmpy.sundials, set up as fmpy's own model-exchange driver sets it
up (BDF, a dense direct linear solver, the absolute tolerances rtol times the state nominals,
root finding on the event indicators), plus what that driver does not offer: one-step mode, the
dense output (CVodeGetDky), a stop time and the step count.

The right-hand side and the root function return -1 (CVODE then stops with a failure flag)
instead of raising inside the ctypes callback, where the exception would be printed and lost;
the first exception is kept in `callback_error` for the caller to report. A Ctrl-C must not
raise there either: while CVODE steps, SIGINT only marks the step interrupted (`HeldInterrupt`),
the callbacks then return -1 at once, and the step raises KeyboardInterrupt once CVODE has
returned."""

from __future__ import annotations

import math
from ctypes import byref, c_int, c_long, c_void_p, cast
from typing import Any

import numpy as np

from ..errors import SimulationError
from ..interrupts import HeldInterrupt

CV_ONE_STEP = 2  # cvode.h (fmpy's binding leaves it commented out)
CV_TSTOP_RETURN = 1  # cvode.h
MAX_NUM_STEPS = 100_000
"""CVODE's limit of internal steps per call (one call is one step here)."""


def _cvode_function(name: str, argtypes: list[Any]) -> Any:
    from fmpy.sundials.cvode import sundials_cvode

    fn = getattr(sundials_cvode, name)
    fn.argtypes, fn.restype = argtypes, c_int
    return fn


class CvodeStepper:
    """CVODE on an fmpy FMU2Model in continuous-time mode with `nx` states and `nz` event
    indicators, from `t0` with relative tolerance `rtol`."""

    def __init__(self, fmu: Any, nx: int, nz: int, rtol: float, t0: float) -> None:
        from fmpy.sundials import cvode, cvode_ls, sunlinsol_dense, sunmatrix_dense
        from fmpy.sundials import nvector_serial as nv
        from fmpy.sundials import sundials_context as ctx
        from fmpy.sundials import sundials_types as types

        self.fmu, self.nx, self.nz, self.rtol = fmu, nx, nz, rtol
        self.realtype = types.sunrealtype
        self.callback_error: BaseException | None = None
        self.interrupt = HeldInterrupt()
        self.error_info: tuple[Any, ...] | None = None
        self.sunctx = types.SUNContext()
        self._check(ctx.SUNContext_Create(types.SUN_COMM_NULL, byref(self.sunctx)))
        self.x = nv.N_VNew_Serial(nx, self.sunctx)
        self.abstol = nv.N_VNew_Serial(nx, self.sunctx)
        self.px, self.pabstol = nv.NV_DATA_S(self.x), nv.NV_DATA_S(self.abstol)
        self._abstol = np.ctypeslib.as_array(self.pabstol, (nx,))
        self._tolerances()
        self.mem = cvode.CVodeCreate(cvode.CV_BDF, self.sunctx)
        # the callbacks live as long as the stepper (ctypes keeps no reference)
        self._f, self._g = cvode.CVRhsFn(self._rhs), cvode.CVRootFn(self._roots)
        self._eh = types.SUNErrHandlerFn(self._error)
        self._check(cvode.CVodeInit(self.mem, self._f, t0, self.x))
        self._check(cvode.CVodeSVtolerances(self.mem, rtol, self.abstol))
        self._check(cvode.CVodeRootInit(self.mem, nz, self._g))
        self.matrix = sunmatrix_dense.SUNDenseMatrix(nx, nx, self.sunctx)
        self.solver = sunlinsol_dense.SUNLinSol_Dense(self.x, self.matrix, self.sunctx)
        self._check(cvode_ls.CVodeSetLinearSolver(self.mem, self.solver, self.matrix))
        self._check(cvode.CVodeSetMaxStep(self.mem, math.inf))
        self._check(cvode.CVodeSetMaxNumSteps(self.mem, MAX_NUM_STEPS))
        self._check(cvode.CVodeSetNoInactiveRootWarn(self.mem))
        self._error_handler()
        real = self.realtype
        self._stop = _cvode_function("CVodeSetStopTime", [c_void_p, real])
        self._dky_fn = _cvode_function("CVodeGetDky", [c_void_p, real, c_int, c_void_p])
        self._num_steps = _cvode_function("CVodeGetNumSteps", [c_void_p, c_void_p])
        self._dky = nv.N_VNew_Serial(nx, self.sunctx)
        self.dky_data = nv.NV_DATA_S(self._dky)
        self._tret, self._nst = real(0.0), c_long(0)

    @staticmethod
    def _check(status: int) -> None:
        if status != 0:
            raise SimulationError(f"CVODE: set-up failed (status {status})")

    def _error_handler(self) -> None:
        """Only our handler, which keeps CVODE's message for the error the caller raises:
        SUNDIALS's default handler would also print it on standard error."""
        clear = _cvode_function("SUNContext_ClearErrHandlers", [c_void_p])
        push = _cvode_function("SUNContext_PushErrHandler", [c_void_p, c_void_p, c_void_p])
        if clear(self.sunctx) != 0 or push(self.sunctx, cast(self._eh, c_void_p), None) != 0:
            raise SimulationError("CVODE: cannot install the error handler")

    def _tolerances(self) -> None:
        """The states from the FMU, the absolute tolerances rtol times its state nominals."""
        self.fmu.getContinuousStates(self.px, self.nx)
        self.fmu.getNominalsOfContinuousStates(self.pabstol, self.nx)
        self._abstol *= self.rtol

    def _error(self, line: int, func: bytes, file: bytes, msg: bytes, code: int, *_: Any) -> None:
        texts = [(b or b"").decode(errors="replace") for b in (func, file, msg)]
        self.error_info = (code, *texts)

    def _rhs(self, t: float, y: Any, ydot: Any, user_data: Any) -> int:
        from fmpy.sundials.nvector_serial import NV_DATA_S

        if self.interrupt.pending:
            return -1  # Ctrl-C: CVODE returns, the step raises KeyboardInterrupt
        try:
            self.fmu.setTime(t)
            self.fmu.setContinuousStates(NV_DATA_S(y), self.nx)
            self.fmu.getDerivatives(NV_DATA_S(ydot), self.nx)
        except BaseException as exc:  # reported by the caller
            self.callback_error = self.callback_error or exc
            return -1
        return 0

    def _roots(self, t: float, y: Any, gout: Any, user_data: Any) -> int:
        from fmpy.sundials.nvector_serial import NV_DATA_S

        if self.interrupt.pending:
            return -1  # Ctrl-C: CVODE returns, the step raises KeyboardInterrupt
        try:
            self.fmu.setTime(t)
            self.fmu.setContinuousStates(NV_DATA_S(y), self.nx)
            self.fmu.getEventIndicators(gout, self.nz)
        except BaseException as exc:  # reported by the caller
            self.callback_error = self.callback_error or exc
            return -1
        return 0

    def step(self, t_out: float) -> tuple[int, float]:
        """One internal step towards t_out: (CVODE's flag, the time reached)."""
        from fmpy.sundials.cvode import CVode

        with self.interrupt:
            flag = CVode(self.mem, t_out, self.x, byref(self._tret), CV_ONE_STEP)
        return int(flag), float(self._tret.value)

    def message(self) -> str:
        """CVODE's message of its last failure."""
        return (self.error_info or ("?", "?", "?", "no message"))[3]

    def dense(self, t: float) -> Any:
        """The interpolated state at t inside the last step (a pointer to nx reals)."""
        self._dky_fn(self.mem, t, 0, self._dky)
        return self.dky_data

    def set_stop_time(self, t: float) -> None:
        self._stop(self.mem, t)

    def steps(self) -> int:
        """Steps since the last (re)initialisation."""
        self._num_steps(self.mem, byref(self._nst))
        return int(self._nst.value)

    def reset(self, t: float) -> None:
        """Restart at t from the FMU's states (after an event)."""
        from fmpy.sundials.cvode import CVodeReInit

        self._tolerances()
        CVodeReInit(self.mem, t, self.x)

    def close(self) -> None:
        from fmpy.sundials.cvode import CVodeFree

        if self.mem:
            CVodeFree(byref(c_void_p(self.mem)))
            self.mem = None
