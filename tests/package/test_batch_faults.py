"""Batched runs under faults (csfh.batch): a sweep killed with SIGKILL leaves no process behind
(its workers and multiprocessing's resource tracker end by themselves) and resumes; two identical
sweeps into one directory at once share the work instead of each computing every run."""

from __future__ import annotations

import os
import subprocess
import sys
import time
from pathlib import Path

import pytest

from csfh.batch.store import ResultStore

LINUX = pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc")

SWEEP = ["sweep", "csfh", "--models", "LN_cylinders", "LN_spheres", "--params", "R1", "m1", "h"]
SWEEP += ["I1", "--stop-time", "1.0", "--quiet"]
"""18 model-exchange runs, some 15 s of work on one core."""


def csfh_process(*args: str, env: dict[str, str] | None = None) -> subprocess.Popen[str]:
    """`python -m csfh ARGS` started in the background (the package this test imports)."""
    return subprocess.Popen(
        [sys.executable, "-m", "csfh", *args],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=env,
    )


def _stat(pid: int) -> list[str] | None:
    """The fields of /proc/PID/stat after the command name (state, ppid, ...), or None."""
    try:
        with open(f"/proc/{pid}/stat", encoding="utf-8") as fh:
            return fh.read().rsplit(")", 1)[1].split()
    except OSError:
        return None


def children(pid: int) -> set[int]:
    kids = set()
    for entry in os.listdir("/proc"):
        fields = _stat(int(entry)) if entry.isdigit() else None
        if fields is not None and int(fields[1]) == pid:
            kids.add(int(entry))
    return kids


def running(pid: int) -> bool:
    fields = _stat(pid)
    return fields is not None and fields[0] not in ("Z", "X")


def wait_for(condition: object, seconds: float) -> bool:
    deadline = time.monotonic() + seconds
    while time.monotonic() < deadline:
        if condition():  # type: ignore[operator]
            return True
        time.sleep(0.1)
    return False


@LINUX
def test_kill_9_of_a_sweep_leaves_no_worker_and_no_resource_tracker(tmp_path: Path) -> None:
    proc = csfh_process(*SWEEP, "--workers", "2", "--out", str(tmp_path))
    kids: set[int] = set()
    try:

        def started() -> bool:
            kids.update(children(proc.pid))
            return len(kids) >= 3 and (tmp_path / "tasks.jsonl").exists()

        assert wait_for(started, 60), "the sweep did not start two workers and finish a run"
        proc.kill()  # SIGKILL: the parent cannot clean up
        proc.wait()
        wait_for(lambda: not any(running(k) for k in kids), 15)
        left = sorted(k for k in kids if running(k))
    finally:
        for k in kids:  # whatever is left, so that a failure leaves nothing behind either
            if running(k):
                os.kill(k, 9)
    assert left == [], f"still running 15 s after the sweep was killed: {left}"
    # the next run resumes from the runs kept, and leaves no temporary file
    kept = len(ResultStore(tmp_path))
    again = csfh_process(*SWEEP, "--workers", "2", "--out", str(tmp_path))
    out, err = again.communicate(timeout=120)
    assert again.returncode == 0, err
    assert f"({18 - kept} computed, {kept} reused" in out
    assert list((tmp_path / "signals").glob(".*.tmp")) == []
