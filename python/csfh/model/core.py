"""ctypes binding to libcsfh_core: the same C physics as the FMU, addressed by the FMU's variable
names. Used by the Moreau stepper and by anything that needs the model's right-hand side without
the FMI layer. Only computation goes through ctypes: what the variables are is the generated
interface's (csfh.model.model_info)."""

from __future__ import annotations

import ctypes
from ctypes import POINTER, c_char_p, c_double, c_int, c_longlong, c_size_t, c_void_p
from functools import cache

import numpy as np

from ..errors import ParameterError
from ..paths import core_library_path
from ._csfh_variables import CORE_ABI_VERSION as ABI_VERSION
from ._csfh_variables import INTERFACE

_MSG = 512
_dp = POINTER(c_double)
N_STATES = len(INTERFACE.states)
N_INPUTS = 3  # csfh_api_set_inputs: F_ext[1], F_ext[2], M_ext


@cache
def library() -> ctypes.CDLL:
    lib = ctypes.CDLL(str(core_library_path()))
    sig = {
        "csfh_api_abi_version": (c_int, []),
        "csfh_api_new": (c_void_p, []),
        "csfh_api_free": (None, [c_void_p]),
        "csfh_api_clone": (c_void_p, [c_void_p]),
        "csfh_api_set": (c_int, [c_void_p, c_char_p, c_double, c_char_p, c_size_t]),
        "csfh_api_get": (c_int, [c_void_p, c_char_p, _dp]),
        "csfh_api_prepare": (c_int, [c_void_p, c_char_p, c_size_t]),
        "csfh_api_set_state": (None, [c_void_p, _dp]),
        "csfh_api_get_state": (None, [c_void_p, _dp]),
        "csfh_api_set_inputs": (None, [c_void_p, _dp]),
        "csfh_api_derivatives": (c_int, [c_void_p, _dp, _dp]),
        "csfh_api_smooth_forces": (None, [c_void_p, _dp, _dp]),
        "csfh_api_event_indicator": (c_double, [c_void_p, _dp]),
        "csfh_api_event_update": (c_int, [c_void_p]),
        "csfh_api_counters": (None, [c_void_p, POINTER(c_longlong)]),
        "csfh_api_moreau_run": (
            c_int,
            [
                c_void_p,
                c_double,
                c_int,
                c_double,
                c_double,
                c_double,
                c_double,
                _dp,
                c_longlong,
                c_longlong,
                _dp,
                c_size_t,
                _dp,
                c_size_t,
                _dp,
                POINTER(c_longlong),
            ],
        ),
        "csfh_api_moreau_record_columns": (c_int, []),
        "csfh_api_moreau_impact_columns": (c_int, []),
        "csfh_api_rk4_run": (
            c_int,
            [
                c_void_p,
                c_double,
                c_double,
                c_double,
                c_double,
                _dp,
                c_double,
                c_double,
                _dp,
                c_size_t,
                _dp,
                c_size_t,
                _dp,
                POINTER(c_longlong),
            ],
        ),
        "csfh_api_rk4_record_columns": (c_int, []),
        "csfh_api_contact_record_columns": (c_int, []),
    }
    for name, (restype, argtypes) in sig.items():
        fn = getattr(lib, name)
        fn.restype = restype
        fn.argtypes = argtypes
    if lib.csfh_api_abi_version() != ABI_VERSION:
        raise RuntimeError(
            f"{core_library_path()} has ABI {lib.csfh_api_abi_version()}, "
            f"expected {ABI_VERSION}: rebuild the package"
        )
    return lib


def _ptr(a: np.ndarray) -> ctypes._Pointer:
    return a.ctypes.data_as(_dp)


class CoreModel:
    """One instance of the C model (parameters, state, inputs, discrete contact state)."""

    def __init__(self, _handle: int | None = None) -> None:
        self._lib = library()
        self._h = _handle if _handle is not None else self._lib.csfh_api_new()
        if not self._h:
            raise MemoryError("csfh_api_new failed")

    def __del__(self) -> None:
        h = getattr(self, "_h", None)
        if h:
            self._lib.csfh_api_free(h)
            self._h = None

    def clone(self) -> CoreModel:
        return CoreModel(self._lib.csfh_api_clone(self._h))

    @property
    def handle(self) -> int:
        return self._h

    def set(self, name: str, value: float | int | bool) -> None:
        msg = ctypes.create_string_buffer(_MSG)
        status = self._lib.csfh_api_set(self._h, name.encode(), float(value), msg, _MSG)
        if status != 0:
            raise ParameterError(msg.value.decode())

    def get(self, name: str) -> float:
        out = c_double()
        if self._lib.csfh_api_get(self._h, name.encode(), ctypes.byref(out)) != 0:
            raise ParameterError(f'unknown variable "{name}"')
        return out.value

    def prepare(self) -> None:
        """Validate every parameter (like fmi2ExitInitializationMode) and derive the constants."""
        msg = ctypes.create_string_buffer(_MSG)
        if self._lib.csfh_api_prepare(self._h, msg, _MSG) != 0:
            raise ParameterError(msg.value.decode())

    @property
    def state(self) -> np.ndarray:
        x = np.empty(N_STATES)
        self._lib.csfh_api_get_state(self._h, _ptr(x))
        return x

    @state.setter
    def state(self, x: np.ndarray) -> None:
        x = np.ascontiguousarray(x, dtype=float)
        if x.shape != (N_STATES,):
            raise ValueError(f"the state has {N_STATES} components [x, y, theta, vx, vy, omega]")
        self._lib.csfh_api_set_state(self._h, _ptr(x))

    def set_inputs(self, u: np.ndarray) -> None:
        u = np.ascontiguousarray(u, dtype=float)
        if u.shape != (N_INPUTS,):
            raise ValueError(f"the inputs are {N_INPUTS} values [F_ext[1], F_ext[2], M_ext]")
        self._lib.csfh_api_set_inputs(self._h, _ptr(u))

    def derivatives(self, x: np.ndarray) -> np.ndarray:
        x = np.ascontiguousarray(x, dtype=float)
        xdot = np.empty(N_STATES)
        status = self._lib.csfh_api_derivatives(self._h, _ptr(x), _ptr(xdot))
        if status < 0:
            raise FloatingPointError(f"non-finite derivative at x = {x.tolist()}")
        return xdot

    def smooth_forces(self, q: np.ndarray) -> np.ndarray:
        q = np.ascontiguousarray(q, dtype=float)
        Q = np.empty(3)
        self._lib.csfh_api_smooth_forces(self._h, _ptr(q), _ptr(Q))
        return Q

    def event_indicator(self, x: np.ndarray) -> float:
        x = np.ascontiguousarray(x, dtype=float)
        return self._lib.csfh_api_event_indicator(self._h, _ptr(x))

    def event_update(self) -> int:
        return self._lib.csfh_api_event_update(self._h)

    def counters(self) -> dict[str, int]:
        out = (c_longlong * 5)()
        self._lib.csfh_api_counters(self._h, out)
        return dict(zip(("rhs", "flexure", "contact", "friction", "steps"), out, strict=True))
