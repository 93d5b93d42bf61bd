"""Batched runs under faults (csfh.batch): a sweep killed with SIGKILL leaves no process behind
(its workers and multiprocessing's resource tracker end by themselves) and resumes; a Dask
scheduler without a worker that runs the tasks, or one that goes away, is one line naming it,
within a time-out, and keeps the finished runs; two identical sweeps into one directory at once
share the runs instead of each computing every one."""

from __future__ import annotations

import json
import os
import re
import signal
import socket
import subprocess
import sys
import time
from collections.abc import Iterator
from contextlib import contextmanager
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


# ------------------------------------------------------------------------------------------
# Dask: no worker that runs the tasks, a scheduler that goes away

DASK = Path(sys.executable).with_name("dask")
BLOCK_CSFH = """
import sys

class _NoCsfh:
    def find_spec(self, name, path=None, target=None):
        if name == "csfh" or name.startswith("csfh."):
            raise ImportError(f"No module named {name!r}")
        return None

sys.meta_path.insert(0, _NoCsfh())
"""


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


@contextmanager
def dask_process(*args: str, env: dict[str, str] | None = None) -> Iterator[subprocess.Popen[str]]:
    """`dask ARGS` (a scheduler or a worker) in the background, ended (by its id) at the end."""
    proc = subprocess.Popen(
        [str(DASK), *args],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
        text=True,
        env=env,
        start_new_session=True,  # its nanny and worker processes go with it
    )
    try:
        yield proc
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
        proc.wait()


@contextmanager
def dask_cluster(worker_env: dict[str, str] | None) -> Iterator[tuple[str, subprocess.Popen[str]]]:
    """A scheduler and one single-threaded worker (with `worker_env`), as subprocesses; the
    scheduler's address and process."""
    distributed = pytest.importorskip("distributed")
    if not DASK.exists():
        pytest.skip("the dask command is not installed")
    address = f"tcp://127.0.0.1:{free_port()}"
    scheduler_args = ["scheduler", "--host", "127.0.0.1", "--port", address.rsplit(":", 1)[1]]
    with dask_process(*scheduler_args, "--no-dashboard") as scheduler:
        worker_args = ["worker", address, "--nworkers", "1", "--nthreads", "1", "--no-dashboard"]
        with dask_process(*worker_args, env=worker_env):
            with distributed.Client(address, timeout="20s") as client:
                client.wait_for_workers(1, timeout=20)
            yield address, scheduler


DASK_SWEEP = ["sweep", "central", "--models", "Moreau", "--params", "R1", "--stop-time", "0.05"]
DASK_SWEEP += ["--quiet"]


def one_error(proc: subprocess.Popen[str], timeout: float) -> str:
    """The one line a failed command writes on standard error."""
    _, err = proc.communicate(timeout=timeout)
    assert proc.returncode == 2, err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("csfh: error: "), err
    return lines[0]


def test_a_dask_scheduler_without_workers_times_out_naming_it(tmp_path: Path) -> None:
    distributed = pytest.importorskip("distributed")
    with distributed.LocalCluster(
        n_workers=0, processes=False, protocol="tcp", host="127.0.0.1", dashboard_address=None
    ) as cluster:
        env = dict(os.environ, CSFH_DASK_TIMEOUT="3")
        start = time.monotonic()
        proc = csfh_process(
            *DASK_SWEEP, "--dask", cluster.scheduler_address, "--out", str(tmp_path), env=env
        )
        try:
            line = one_error(proc, 60)
        finally:
            proc.kill()
        assert cluster.scheduler_address in line and "no Dask worker" in line, line
        assert time.monotonic() - start < 30


def test_dask_workers_that_cannot_import_csfh_time_out(tmp_path: Path) -> None:
    (tmp_path / "hook").mkdir()
    (tmp_path / "hook" / "sitecustomize.py").write_text(BLOCK_CSFH)
    worker_env = dict(os.environ, PYTHONPATH=str(tmp_path / "hook"))
    with dask_cluster(worker_env) as (address, _):
        env = dict(os.environ, CSFH_DASK_TIMEOUT="5")
        proc = csfh_process(*DASK_SWEEP, "--dask", address, "--out", str(tmp_path / "o"), env=env)
        try:
            line = one_error(proc, 60)
        finally:
            proc.kill()
        assert address in line and "csfh" in line, line


def test_a_dask_scheduler_killed_mid_run_is_one_line_and_the_rerun_resumes(
    tmp_path: Path,
) -> None:
    with dask_cluster(None) as (address, scheduler):
        proc = csfh_process(*SWEEP, "--dask", address, "--out", str(tmp_path))
        try:
            assert wait_for(lambda: len(ResultStore(tmp_path)) >= 2, 60), "no run finished"
            os.killpg(scheduler.pid, signal.SIGKILL)
            line = one_error(proc, 60)
        finally:
            proc.kill()
    assert address in line and "kept" in line, line
    kept = len(ResultStore(tmp_path))
    assert 2 <= kept < 18
    again = csfh_process(*SWEEP, "--workers", "2", "--out", str(tmp_path))
    out, err = again.communicate(timeout=120)
    assert again.returncode == 0, err
    assert f"({18 - kept} computed, {kept} reused" in out


# ------------------------------------------------------------------------------------------
# two identical sweeps at once

TWIN = ["sweep", "central", "--models", "LN_cylinders", "LN_spheres", "--params", "R1", "m1", "h"]
TWIN += ["--stop-time", "0.3", "--workers", "1"]
"""14 model-exchange runs, some 6 s of work on one core."""


def test_two_identical_sweeps_at_once_share_the_runs(tmp_path: Path) -> None:
    procs = [csfh_process(*TWIN, "--out", str(tmp_path)) for _ in range(2)]
    try:
        outputs = [p.communicate(timeout=180) for p in procs]
    finally:
        for p in procs:
            p.kill()
    assert [p.returncode for p in procs] == [0, 0], [err for _, err in outputs]
    counts = [
        re.search(r"sweep: 14 runs \((\d+) computed, (\d+) reused", out) for out, _ in outputs
    ]
    assert all(counts), outputs
    computed = [int(m.group(1)) for m in counts if m]
    assert sum(computed) == 14, f"the two sweeps computed {computed} of the 14 runs"
    keys = [json.loads(line)["key"] for line in (tmp_path / "tasks.jsonl").read_text().splitlines()]
    assert len(keys) == len(set(keys)) == 14
    # the same report: every line but the last (which says what was computed and reused)
    reports = [out.strip().splitlines()[:-1] for out, _ in outputs]
    assert reports[0] == reports[1] and reports[0]
    assert list((tmp_path / "claims").iterdir()) == []


CLAIMER = """
import sys, time
from csfh.batch.store import ResultStore
with ResultStore(sys.argv[1]).claimed(sys.argv[2:]) as mine:
    print(len(mine), flush=True)
    time.sleep(600)
"""


def test_the_claims_of_a_killed_command_are_taken_over(tmp_path: Path) -> None:
    keys = [f"{k:024x}" for k in range(5)]
    claimer = subprocess.Popen(
        [sys.executable, "-c", CLAIMER, str(tmp_path), *keys[:3]], stdout=subprocess.PIPE, text=True
    )
    try:
        assert claimer.stdout is not None and claimer.stdout.readline().strip() == "3"
        store = ResultStore(tmp_path)
        with store.claimed(keys) as mine:
            assert mine == set(keys[3:])  # the other command's runs are left to it
        claimer.kill()  # SIGKILL: its claim file stays, its lock does not
        claimer.wait()
        assert len(list((tmp_path / "claims").iterdir())) == 1
        with store.claimed(keys) as mine:
            assert mine == set(keys)
            assert len(list((tmp_path / "claims").iterdir())) == 1  # this command's own
        assert list((tmp_path / "claims").iterdir()) == []
    finally:
        claimer.kill()
        claimer.wait()
