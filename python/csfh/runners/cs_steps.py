"""The communication loop of `simulate_cs` in C: fmi2DoStep and the reads of fixed sets of
outputs for a chunk of communication steps in one ctypes call (csfh_cs_steps in the batch library
libcsfh_batch.so, fmu_src/masters/csfh_cs_steps.c), on our instance of the FMU
(`fmi2_slave.Fmi2Slave`: the addresses of its binary's fmi2 functions and of the instance).

From Python, every FMI call through ctypes costs about 1 us beyond the FMU's own work (the call,
and the FMU's code and data no longer in the caches after the interpreter's work between calls):
on a fine communication grid, or on a run of few steps timed against a compiled integrator, that
is most of the time. Here Python pays one call per chunk of steps. The grid is simulate_cs's,
computed the same way as Python would (t_next = min((k + 1) h, t_end), steps t_next - t): the
tests compare it with a loop in Python, bitwise (tests/package/test_cs_steps.py)."""

from __future__ import annotations

import ctypes
from collections.abc import Sequence
from ctypes import POINTER, Structure, c_double, c_int, c_longlong, c_size_t, c_uint, c_void_p
from dataclasses import dataclass
from functools import cache
from time import perf_counter
from typing import Any

import numpy as np

from .. import paths
from ..errors import InstallError
from ..interrupts import HeldInterrupt
from ..model._csfh_variables import BATCH_ABI_VERSION as ABI_VERSION
from .fmi2_slave import FmiCallError

_CALLS = ("fmi2DoStep", "fmi2GetReal", "fmi2GetInteger", "fmi2GetBoolean")
"""The calls csfh_cs_steps reports as failed (CSFH_STEPS_DO_STEP .. _GET_BOOLEAN)."""


class _Loop(Structure):
    _fields_ = [
        ("do_step", c_void_p),
        ("get_real", c_void_p),
        ("get_integer", c_void_p),
        ("get_boolean", c_void_p),
        ("component", c_void_p),
        ("step", c_double),
        ("stop_time", c_double),
        ("n_real", c_size_t),
        ("real_vr", POINTER(c_uint)),
        ("n_integer", c_size_t),
        ("integer_vr", POINTER(c_uint)),
        ("n_boolean", c_size_t),
        ("boolean_vr", POINTER(c_uint)),
    ]


@cache
def library() -> Any:
    """The batch library (libcsfh_batch.so: the batch master of cs_batch and csfh_cs_steps),
    loaded once per process, its ABI checked."""
    lib = ctypes.CDLL(str(paths.batch_library_path()))
    lib.csfh_cs_batch_abi_version.restype = c_int
    if lib.csfh_cs_batch_abi_version() != ABI_VERSION:
        raise InstallError(
            f"{paths.batch_library_path()} has ABI version {lib.csfh_cs_batch_abi_version()}, this "
            f"package needs {ABI_VERSION}: rebuild or reinstall csfh"
        )
    lib.csfh_cs_steps.restype = c_longlong
    lib.csfh_cs_steps.argtypes = [
        POINTER(_Loop),
        c_longlong,
        c_longlong,
        c_double,
        c_void_p,
        c_void_p,
        c_void_p,
        c_void_p,
        POINTER(c_int),
    ]
    return lib


def available() -> bool:
    """Whether the batch library is there."""
    try:
        paths.batch_library_path()
    except FileNotFoundError:
        return False
    return True


@dataclass
class Chunk:
    """The outputs after steps k_first .. k_first + done - 1 (rows 0 .. done - 1)."""

    times: np.ndarray  # the grid times reached
    reals: np.ndarray  # done x n_real
    integers: np.ndarray  # done x n_integer (int32)
    booleans: np.ndarray  # done x n_boolean (int32, fmi2Boolean)
    done: int
    seconds: float  # wall time inside the C call


class CSteps:
    """Chunks of communication steps of an instantiated, initialised instance (which stays the
    owner of the instance: `address(name)` of its fmi2 functions, `component`) on the grid
    min((k + 1) h, t_end), reading fixed value references after every step."""

    def __init__(
        self,
        slave: Any,
        step: float,
        stop_time: float,
        reals: Sequence[int],
        integers: Sequence[int] = (),
        booleans: Sequence[int] = (),
    ) -> None:
        self._lib = library()
        address = slave.address
        self._refs = [(c_uint * len(r))(*r) for r in (reals, integers, booleans)]
        self._loop = _Loop(
            address("fmi2DoStep"),
            address("fmi2GetReal"),
            address("fmi2GetInteger"),
            address("fmi2GetBoolean"),
            slave.component,
            step,
            stop_time,
            len(reals),
            self._refs[0],
            len(integers),
            self._refs[1],
            len(booleans),
            self._refs[2],
        )
        self.counts = (len(reals), len(integers), len(booleans))
        self._failure = (c_int * 2)()
        self._capacity = 0
        self._grow(0)

    def _grow(self, rows: int) -> None:
        """Output buffers for chunks of up to `rows` steps, re-used from chunk to chunk, and
        their addresses: numpy's ctypes addresses cost ~2 us each, as much as a communication
        step of the FMU, so they are taken once per buffer, not per call."""
        nr, ni, nb = self.counts
        self._capacity = rows
        self._times = np.empty(rows)
        self._reals = np.empty((rows, nr))
        self._integers = np.empty((rows, ni), dtype=np.int32)
        self._booleans = np.empty((rows, nb), dtype=np.int32)
        self._addresses = tuple(
            a.ctypes.data for a in (self._times, self._reals, self._integers, self._booleans)
        )

    def run(self, k_first: int, k_last: int, t: float) -> Chunk:
        """Steps k_first .. k_last - 1 from time t (the grid time before step k_first). Raises
        FmiCallError for a call that returned fmi2Error or worse, with `t` (the time
        the failed step started from, or reached if reading its outputs failed) and `chunk` (the
        steps before it) attached."""
        m = k_last - k_first
        if m > self._capacity:
            self._grow(m)
        times, reals, integers, booleans = self._addresses
        with HeldInterrupt():  # the FMU's logger is a Python callback
            t0 = perf_counter()
            done = self._lib.csfh_cs_steps(
                self._loop, k_first, k_last, t, times, reals, integers, booleans, self._failure
            )
            seconds = perf_counter() - t0
        if done < 0:
            raise ValueError(f"csfh_cs_steps: bad arguments (steps {k_first} .. {k_last})")
        # copies: the buffers are the next chunk's
        rows = slice(0, max(done, 0))
        chunk = Chunk(
            self._times[rows].copy(),
            self._reals[rows].copy(),
            self._integers[rows].copy(),
            self._booleans[rows].copy(),
            done,
            seconds,
        )
        call, status = self._failure
        if call >= 0:
            reached = call > 0  # fmi2DoStep went through, reading its outputs failed
            exc = FmiCallError(
                _CALLS[call],
                status,
                float(self._times[done])
                if reached
                else float(self._times[done - 1])
                if done
                else t,
            )
            exc.chunk = chunk
            raise exc
        return chunk
