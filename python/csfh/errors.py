"""The errors csfh reports to its users. Each message names what is wrong (the file, the key or
the variable, and its value), so that the command line reports it on one line (exit status 2)."""

from __future__ import annotations


class SceneError(ValueError):
    """A scene file that cannot be used; the message says which key and why."""


class ParameterError(ValueError):
    """A parameter value the model rejects; the message names the variable and the value."""


class SimulationError(RuntimeError):
    """The integration failed; the message says where and why."""


class ResultsError(ValueError):
    """A results folder that csfh refuses to use as it is (a state file changed by hand or by
    another program, a path leading out of the folder, a special file where a result goes); the
    message names the file."""


class BatchError(RuntimeError):
    """Batched runs that cannot go on (a Dask scheduler that went away or has no worker that
    runs the tasks); the message names the executor. Finished runs are kept."""


USER_ERRORS: tuple[type[BaseException], ...] = (
    SceneError,
    ParameterError,
    SimulationError,
    ResultsError,
    BatchError,
    FileNotFoundError,
    ValueError,
    FloatingPointError,
    OSError,
)
"""What the command line reports as one line with exit status 2 (bad input, a failed run, a file
that cannot be read or written), rather than as a traceback."""
