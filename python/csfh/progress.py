"""Progress bars on standard error, drawn by tqdm: only on a terminal, never when quiet, and only
for work that takes longer than a second.

Two kinds: a fraction of one run (`update(fraction)`, e.g. the simulated time over the stop time;
no time estimate, since contacts make the rate uneven), and a count of runs (`total=N`,
`update(done)`, with the estimated time left)."""

from __future__ import annotations

import sys
from typing import Any, TextIO


class Progress:
    """Call update(...) as work proceeds and close() at the end."""

    def __init__(
        self,
        label: str,
        quiet: bool = False,
        *,
        total: int | None = None,
        unit: str = "run",
        stream: TextIO | None = None,
        delay: float = 1.0,
    ) -> None:
        self.label = label
        self.total = total
        self.stream = stream or sys.stderr
        self.enabled = not quiet and self.stream.isatty()
        self._bar: Any = None
        if not self.enabled:
            return
        from tqdm import tqdm

        if total is None:  # a fraction of one run, in per mille
            self._bar = tqdm(
                total=1000,
                desc=label,
                file=self.stream,
                delay=delay,
                leave=False,
                dynamic_ncols=True,
                bar_format="{desc} {percentage:3.0f}%|{bar}| {elapsed}",
            )
        else:
            self._bar = tqdm(
                total=total,
                desc=label,
                unit=unit,
                file=self.stream,
                delay=delay,
                leave=False,
                dynamic_ncols=True,
            )

    def update(self, done: float) -> None:
        """The fraction done (0 ... 1), or the number of runs done when a total was given."""
        if self._bar is None:
            return
        position = round(1000 * min(max(done, 0.0), 1.0)) if self.total is None else done
        step = int(position) - self._bar.n
        if step > 0:
            self._bar.update(step)

    def close(self) -> None:
        """Remove the bar (the command prints its own summary)."""
        if self._bar is not None:
            self._bar.close()
            self._bar = None
