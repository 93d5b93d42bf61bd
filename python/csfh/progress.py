"""A terminal progress bar that appears only for work longer than a second."""

from __future__ import annotations

import sys
import time
from typing import TextIO


class Progress:
    """Call update(fraction) as work proceeds; close() at the end. Silent when quiet, when the
    stream is not a terminal, or until a second has passed."""

    def __init__(
        self, label: str, quiet: bool = False, stream: TextIO | None = None, delay: float = 1.0
    ) -> None:
        self.label = label
        self.stream = stream or sys.stderr
        self.enabled = not quiet and self.stream.isatty()
        self.start = time.perf_counter()
        self.delay = delay
        self._last = 0.0
        self._shown = False

    def update(self, fraction: float) -> None:
        if not self.enabled:
            return
        now = time.perf_counter()
        if now - self.start < self.delay or now - self._last < 0.1:
            return
        self._last = now
        fraction = min(max(fraction, 0.0), 1.0)
        width = 30
        filled = int(width * fraction)
        elapsed = now - self.start
        eta = elapsed * (1 - fraction) / fraction if fraction > 0 else float("nan")
        self.stream.write(
            f"\r{self.label:<28} [{'#' * filled}{'.' * (width - filled)}] "
            f"{100 * fraction:5.1f}%  {elapsed:6.1f}s  eta {eta:5.1f}s"
        )
        self.stream.flush()
        self._shown = True

    def close(self) -> None:
        if self._shown:
            self.stream.write(
                f"\r{self.label:<28} done in {time.perf_counter() - self.start:.1f}s"
                + " " * 40
                + "\n"
            )
            self.stream.flush()
