"""The errors csfh reports to its users. Each message names what is wrong (the file, the key or
the variable, and its value), so that the command line reports it on one line (exit status 2).

Every user error is a `CsfhError`; the command line reports those (and an exhausted memory) on
one line and lets anything else, a bug, show its traceback. Each type also derives from the
built-in exception it stands for (a scene or a parameter is a bad value, a missing binary a
missing file), so that code catching the built-in one keeps working."""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager


class CsfhError(Exception):
    """A problem with the user's input, files or installation, not a bug in csfh."""


class SceneError(CsfhError, ValueError):
    """A scene file that cannot be used; the message says which key and why."""


class ParameterError(CsfhError, ValueError):
    """A parameter or option value the model or a runner rejects; the message names it and its
    value."""


class SimulationError(CsfhError, RuntimeError):
    """The integration failed; the message says where and why."""


class ResultsError(CsfhError, ValueError):
    """An output or results folder (or a file in it) that csfh cannot use or refuses to use as
    it is: it cannot be read or written, a state file changed by hand or by another program, a
    path leading out of the folder, a special file where a result goes; the message names the
    path and the reason."""


class BatchError(CsfhError, RuntimeError):
    """Batched runs that cannot go on (a Dask scheduler that went away or has no worker that
    runs the tasks); the message names the executor. Finished runs are kept."""


class InstallError(CsfhError, FileNotFoundError):
    """A binary the package needs (an FMU, a ctypes library) is missing or unusable; the message
    says which and where it was looked for."""


class CliError(CsfhError):
    """A command-line argument that cannot be used; the message names the option and value."""


USER_ERRORS: tuple[type[BaseException], ...] = (CsfhError, MemoryError)
"""What the command line reports as one line with exit status 2 (bad input, a failed run, a file
that cannot be read or written, memory exhausted), rather than as a traceback."""


def file_error(path: object, exc: OSError, what: str = "cannot be written") -> ResultsError:
    """A ResultsError naming the path and the system's reason (no raw errno)."""
    reason = exc.strerror or str(exc) or type(exc).__name__
    return ResultsError(f"{path}: {what} ({reason})")


@contextmanager
def file_errors(path: object, what: str = "cannot be written") -> Iterator[None]:
    """Inside the block, an OSError of the file system becomes a ResultsError naming `path` (not
    a temporary file's name) and the system's reason."""
    try:
        yield
    except ResultsError:
        raise
    except OSError as exc:
        raise file_error(path, exc, what) from None
