"""Executors of batched runs, with bitwise-identical results: serial in this process, local
processes, or a Dask distributed cluster. Each computes the tasks not yet in the store (chunks of
`csfh.batch.tasks.run_chunk`) and adds every result as it completes."""

from __future__ import annotations

import hashlib
import math
import multiprocessing
import os
import signal
import time
from collections.abc import Callable, Iterable, Iterator, Sequence
from concurrent.futures import FIRST_COMPLETED, CancelledError, Future, ProcessPoolExecutor, wait
from contextlib import contextmanager, suppress
from dataclasses import dataclass
from typing import Any

from ..errors import BatchError, InstallError, ParameterError
from ..progress import Progress
from .store import ResultStore
from .tasks import Result, Task, batch_group, run_chunk, worker_init


def default_workers() -> int:
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # not Linux
        return max(1, os.cpu_count() or 1)


def make_chunks(tasks: Sequence[Task], workers: int, batch: int = 64) -> list[list[Task]]:
    """Tasks that run as one batch (Moreau, and co-simulation: `batch_group`) grouped into
    chunks of at most `batch`, small enough to keep every worker busy; model-exchange tasks one
    per chunk. Deterministic."""
    groups: dict[tuple[Any, ...], list[Task]] = {}
    chunks: list[list[Task]] = []
    for t in tasks:
        gk = batch_group(t)
        if gk is not None:
            groups.setdefault(gk, []).append(t)
        else:
            chunks.append([t])
    for group in groups.values():
        size = max(1, min(batch, math.ceil(len(group) / max(1, workers))))
        chunks += [group[i : i + size] for i in range(0, len(group), size)]
    return chunks


@dataclass
class RunReport:
    total: int
    reused: int
    computed: int
    wall_time: float
    executor: str


def run_tasks(
    tasks: Sequence[Task],
    store: ResultStore,
    *,
    workers: int | None = None,
    dask_address: str | None = None,
    label: str = "tasks",
    quiet: bool = False,
    batch: int = 64,
    on_result: Callable[[int, int], None] | None = None,
) -> RunReport:
    """Compute the tasks not yet in `store` and add their results as they complete. workers=1
    runs serially in this process; more uses that many local processes (default: all cores);
    dask_address sends the chunks to a Dask distributed scheduler. Tasks that another command
    on the same store has claimed are not computed again: their results are waited for (and
    computed here if that command ends without them). Ctrl-C (KeyboardInterrupt) propagates
    after pending work is cancelled; everything finished so far is in the store."""
    unique: dict[str, Task] = {}
    for t in tasks:
        unique.setdefault(t.key, t)
    pending = {k: t for k, t in unique.items() if k not in store}
    n_workers = default_workers() if workers is None else max(1, workers)
    progress = Progress(label, quiet=quiet, total=len(pending))
    done, elsewhere, executor = 0, 0, "none (all reused)"
    wall = time.perf_counter()

    def accept(results: Iterable[Result]) -> None:
        nonlocal done
        batch = [(pending[key], summary, sig, wall) for key, summary, sig, wall in results]
        store.add_many(batch)
        done += len(batch)
        progress.update(done + elsewhere)
        if on_result is not None:
            on_result(done, len(pending))

    try:
        while left := [t for k, t in pending.items() if k not in store]:
            with store.claimed([t.key for t in left]) as mine:
                if mine:
                    todo = [t for t in left if t.key in mine]
                    executor = _execute(todo, accept, n_workers, dask_address, batch)
            if not mine:  # all claimed by other commands: wait for their results
                time.sleep(CLAIM_POLL)
            elsewhere += len(store.refresh().intersection(pending))
            progress.update(done + elsewhere)
    finally:
        progress.close()
    return RunReport(
        total=len(unique),
        reused=len(unique) - done,
        computed=done,
        wall_time=time.perf_counter() - wall,
        executor=executor,
    )


CLAIM_POLL = 0.5
"""Seconds between looks at the store while another command computes the claimed runs."""


def _execute(
    tasks: list[Task],
    accept: Callable[[Iterable[Result]], None],
    n_workers: int,
    dask_address: str | None,
    batch: int,
) -> str:
    """Compute `tasks` in chunks on the executor chosen (see `run_tasks`); what it was."""
    chunks = make_chunks(tasks, n_workers if dask_address is None else max(n_workers, 8), batch)
    if dask_address is not None:
        _run_dask(chunks, dask_address, accept, dask_timeout())
        return f"dask {dask_address}"
    if n_workers == 1 or len(chunks) == 1:
        for chunk in chunks:
            accept(run_chunk(chunk))
        return "serial"
    _run_processes(chunks, n_workers, accept)
    return f"{n_workers} local processes"


@contextmanager
def _sigint_blocked() -> Iterator[None]:
    """SIGINT held back in this thread (delivered when the block ends, never lost). Processes
    started meanwhile inherit the block: a Ctrl-C while a worker starts up and imports csfh
    stays pending there until `worker_init` ignores it, instead of a KeyboardInterrupt traceback
    from every worker."""
    if not hasattr(signal, "pthread_sigmask"):  # not POSIX
        yield
        return
    old = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, old)


def _stop_pool(pool: ProcessPoolExecutor) -> None:
    """End a pool now: pending chunks cancelled, running ones abandoned (the workers ignore
    Ctrl-C, so they are terminated), the executor's own thread left to wind down without errors.
    What was accepted is in the store already."""
    # the pool's worker processes (a private attribute: the public API cannot end them)
    workers = list((getattr(pool, "_processes", None) or {}).values())
    pool.shutdown(wait=False, cancel_futures=True)
    for proc in workers:
        if proc.is_alive():
            proc.terminate()
    for proc in workers:
        proc.join(timeout=10)


def _run_processes(
    chunks: list[list[Task]], workers: int, accept: Callable[[Iterable[Result]], None]
) -> None:
    ctx = multiprocessing.get_context("spawn")
    pool = ProcessPoolExecutor(
        max_workers=min(workers, len(chunks)),
        mp_context=ctx,
        initializer=worker_init,
        initargs=(os.getpid(),),  # a worker ends with this process, even after a SIGKILL
    )
    futures: set[Future[list[Result]]] = set()
    try:
        # largest chunks first (Moreau batches, then runs), a bounded number in flight
        queue = sorted(chunks, key=len)
        while queue or futures:
            while queue and len(futures) < 2 * workers:
                with _sigint_blocked():  # a submit may start a worker process
                    futures.add(pool.submit(run_chunk, queue.pop()))
            finished, futures = wait(futures, return_when=FIRST_COMPLETED)
            for fut in finished:
                accept(fut.result())
    except BaseException:
        _stop_pool(pool)
        raise
    pool.shutdown(wait=True)


DASK_TIMEOUT = 60.0
"""Seconds a Dask run waits, while no worker is connected to the scheduler and no result comes
in, before it gives up (CSFH_DASK_TIMEOUT overrides it)."""


def dask_timeout() -> float:
    """$CSFH_DASK_TIMEOUT (seconds > 0), else DASK_TIMEOUT."""
    text = os.environ.get("CSFH_DASK_TIMEOUT", "").strip()
    if not text:
        return DASK_TIMEOUT
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not (value > 0 and math.isfinite(value)):
        raise ParameterError(f"$CSFH_DASK_TIMEOUT = {text!r}: a time-out in seconds > 0")
    return value


@contextmanager
def _dask_logs_quiet() -> Iterator[None]:
    """Dask's own log records held back (a lost scheduler is reported on one line instead of
    the client's tracebacks on standard error); restored afterwards."""
    import logging

    names = [n for n in logging.root.manager.loggerDict if n.split(".")[0] in ("distributed",)]
    loggers = [logging.getLogger(n) for n in ("distributed", *names)]
    levels = [logger.level for logger in loggers]
    for logger in loggers:
        logger.setLevel(logging.CRITICAL + 1)
    try:
        yield
    finally:
        for logger, level in zip(loggers, levels, strict=True):
            logger.setLevel(level)


def _run_dask(
    chunks: list[list[Task]],
    address: str,
    accept: Callable[[Iterable[Result]], None],
    timeout: float,
) -> None:
    try:
        from distributed import Client
    except ImportError as exc:  # pragma: no cover - depends on the installation
        raise InstallError(
            "--dask needs dask.distributed: pip install 'dask[distributed]'"
        ) from exc
    with _dask_logs_quiet():
        try:
            client = Client(address, timeout="10s")
        except (OSError, TimeoutError) as exc:
            raise BatchError(f"cannot connect to the Dask scheduler at {address}: {exc}") from None
        futures = []
        try:
            for chunk in chunks:
                ckey = hashlib.sha256("".join(t.key for t in chunk).encode()).hexdigest()[:16]
                futures.append(
                    client.submit(run_chunk, chunk, key=f"csfh-chunk-{ckey}", pure=False)
                )
            _collect(client, futures, address, accept, timeout)
        except BaseException:
            with suppress(Exception):
                client.cancel(futures)
            raise
        finally:
            with suppress(Exception):
                client.close(timeout=5)


def _collect(
    client: Any,
    futures: list[Any],
    address: str,
    accept: Callable[[Iterable[Result]], None],
    timeout: float,
) -> None:
    """Accept the results of `futures` as they complete. A scheduler that has had no worker
    (none started, all gone, or every one ended by a task it could not load) for `timeout` s
    while no result came in ends the run with a BatchError naming it, and so does a scheduler
    that went away (`_next_results`)."""
    pending, idle_since = set(futures), time.monotonic()
    while pending:
        results, pending, connected = _next_results(client, pending, address)
        for result in results:
            accept(result)
        if results or connected:
            idle_since = time.monotonic()
        elif time.monotonic() - idle_since > timeout:
            raise BatchError(
                f"no Dask worker at {address} has run a task for {timeout:g} s (none is "
                f"connected, or none can import csfh); {_KEPT} when workers with the same csfh "
                "build are connected (CSFH_DASK_TIMEOUT sets the wait)"
            )


_KEPT = "the finished runs are kept: the same command resumes"


def _next_results(
    client: Any, pending: set[Any], address: str
) -> tuple[list[list[Result]], set[Any], bool]:
    """The results that complete within a second, the futures still pending, and whether a
    worker is connected. A lost scheduler (the connection, cancelled futures) and workers that
    cannot load the tasks are a BatchError naming the scheduler; an error of a task itself is
    raised as it is."""
    from distributed import KilledWorker
    from distributed import wait as dask_wait

    try:
        try:
            done, pending = dask_wait(pending, timeout=1.0, return_when="FIRST_COMPLETED")
        except TimeoutError:
            done = set()
        connected = bool(done) or bool(client.nthreads())
    except (CancelledError, OSError) as exc:
        raise _lost(address, exc) from None
    try:
        return [fut.result() for fut in done], pending, connected
    except CancelledError as exc:
        raise _lost(address, exc) from None
    except (KilledWorker, ImportError) as exc:
        raise BatchError(
            f"the Dask workers of {address} cannot run csfh's tasks ({type(exc).__name__}: "
            f"{exc}); are they of the same csfh build? {_KEPT}"
        ) from None


def _lost(address: str, exc: BaseException) -> BatchError:
    return BatchError(
        f"the Dask scheduler at {address} went away or cancelled the tasks "
        f"({type(exc).__name__}); {_KEPT}"
    )
