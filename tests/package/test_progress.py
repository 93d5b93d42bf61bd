"""The progress line (csfh.progress): shown on a terminal and leaving it clean, silent when quiet
or not a terminal."""

from __future__ import annotations

import io

import pytest

from csfh.progress import Progress


class Terminal(io.StringIO):
    """A stream that says it is a terminal; `screen` is what a terminal would show."""

    def isatty(self) -> bool:
        return True

    def screen(self) -> list[str]:
        lines = [""]
        col = 0
        for ch in self.getvalue():
            if ch == "\r":
                col = 0
            elif ch == "\n":
                lines.append("")
                col = 0
            else:
                line = lines[-1]
                lines[-1] = line[:col].ljust(col) + ch + line[col + 1 :]
                col += 1
        return [line.rstrip() for line in lines]


@pytest.mark.parametrize("total", [None, 40])
def test_progress_shows_on_a_terminal_and_leaves_it_clean(total: int | None) -> None:
    term = Terminal()
    progress = Progress("central: LN_spheres", stream=term, delay=0.0, total=total)
    for k in range(41):
        progress.update(k if total else k / 40)
    assert "central: LN_spheres" in term.screen()[-1]
    progress.close()
    assert "\x1b" not in term.getvalue()  # plain carriage returns only
    assert term.screen() == [""], term.screen()


def test_progress_is_silent_when_quiet_or_not_a_terminal() -> None:
    quiet = Terminal()
    progress = Progress("x", quiet=True, stream=quiet, delay=0.0)
    progress.update(0.5)
    progress.close()
    piped = io.StringIO()
    progress = Progress("x", stream=piped, delay=0.0)
    progress.update(0.5)
    progress.close()
    assert quiet.getvalue() == "" and piped.getvalue() == ""
