"""Ctrl-C while C code runs that may call back into Python.

A KeyboardInterrupt raised inside a ctypes callback (an integrator's right-hand side, the FMU's
logger) is printed ("Exception ignored on calling ctypes callback function") and lost. Inside a
`HeldInterrupt` block SIGINT only marks the block interrupted, and KeyboardInterrupt is raised
when the block ends, back in Python."""

from __future__ import annotations

import signal
import threading
from types import FrameType
from typing import Any


class HeldInterrupt:
    """A block in which SIGINT sets `pending` instead of raising KeyboardInterrupt (which,
    raised inside a ctypes callback, would be printed and lost); KeyboardInterrupt is raised
    when the block ends. Only where Python's own SIGINT handler is in place (the main thread;
    not in worker processes, which ignore SIGINT)."""

    def __init__(self) -> None:
        self.pending = False
        self._previous: Any = None

    def _handler(self, signum: int, frame: FrameType | None) -> None:
        self.pending = True

    def __enter__(self) -> HeldInterrupt:
        self.pending = False
        held = threading.current_thread() is threading.main_thread() and (
            signal.getsignal(signal.SIGINT) is signal.default_int_handler
        )
        self._previous = signal.signal(signal.SIGINT, self._handler) if held else None
        return self

    def __exit__(self, *exc: object) -> None:
        if self._previous is not None:
            signal.signal(signal.SIGINT, self._previous)
            self._previous = None
        if self.pending and exc[0] is None:
            raise KeyboardInterrupt
