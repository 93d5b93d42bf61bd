#!/usr/bin/env python3
"""Mutation check of the test suite: apply small deliberate bugs (mutants) to the sources one at a
time, rebuild, run the tests chosen for each, and report which mutants the tests catch and which
survive. Run on demand (it takes a while), not in CI:

    tools/mutants.py                      # every mutant of tools/mutants.toml
    tools/mutants.py --only 'moreau-*'    # some of them (shell-style patterns)
    tools/mutants.py --list               # what the list holds
    tools/mutants.py --check              # every mutant still applies to the sources (fast)

The sources are never touched: the tool copies the working tree (the files git knows of, with
their current, possibly uncommitted, contents) into a scratch directory, builds and mutates
there, and removes it at the end, however the run ends (error, Ctrl-C, SIGTERM); the commands
it started are killed with it. --workdir DIR keeps the copy and its build for the next run
(only changed files are rewritten, so the next build is incremental).

A mutant is an exact search/replace in one file (the search text must occur exactly once, or
the mutant is reported "stale": the list has to follow the code). Its tests are given per
runner (the list's [runners]: C tests by ctest name, Python tests by pytest node id). A mutant
is "caught" when a test fails; with each_layer = true every runner must catch it on its own
(the physics checked in C and in Python). Before the mutants, the chosen tests run once on the
unmodified copy: they must pass, or nothing is measured. Statuses: caught, survived, invalid
(the mutant does not build), stale, timeout (counted as caught, reported apart).

The list (TOML):

    [settings]
    setup = [["cmake", "-S", ".", "-B", "build"]]      # once, in the copy
    build = [["cmake", "--build", "build"]]            # after every change
    timeout = 1800                                     # s, per command

    [runners.Python]
    command = ["{python}", "-m", "pytest", "-q", "-x", "{tests}"]

    [[mutant]]
    name = "moreau-m-for-I"
    file = "fmu_src/solvers/csfh_moreau.c"
    search = "1.0 / m->p.I1}"
    replace = "1.0 / m->p.m1}"
    why = "the rotation must use the inertia"
    each_layer = true
    tests = { C = ["test_moreau"], Python = ["tests/package/test_moreau.py::test_x"] }

In commands: {python} is this interpreter, {jobs} the build parallelism (--jobs), {source} the
source tree (e.g. for a download cache kept there), {tests} the mutant's tests for that runner
(one argument each), {regex} them as one anchored alternation ^(a|b)$ (for ctest -R).
Commands run in the copy with PYTHONPATH=<copy>/python, and without the CSFH_FMU/CSFH_CORE/
CSFH_COMBDRIVE_FMU overrides, so the tests use the copy's build.

Exit status: 0 every mutant caught, 1 some survived (or invalid, stale), 2 bad list, failed
baseline or set-up, 130 interrupted.
"""

from __future__ import annotations

import argparse
import fnmatch
import json
import os
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import time
import tomllib
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
DEFAULT_LIST = ROOT / "tools" / "mutants.toml"
ENV_DROPPED = ("CSFH_FMU", "CSFH_CORE", "CSFH_COMBDRIVE_FMU")
SKIPPED_DIRS = {".git", ".venv", "__pycache__", ".pytest_cache", ".ruff_cache"}


class ListError(Exception):
    """The mutant list is malformed."""


class Interrupted(Exception):
    """SIGINT or SIGTERM arrived."""


@dataclass(frozen=True)
class Mutant:
    name: str
    file: str
    search: str
    replace: str
    tests: dict[str, list[str]]
    why: str = ""
    each_layer: bool = False


@dataclass
class Settings:
    setup: list[list[str]] = field(default_factory=list)
    build: list[list[str]] = field(default_factory=list)
    timeout: float = 1800.0
    runners: dict[str, list[str]] = field(default_factory=dict)


@dataclass
class Outcome:
    status: str  # caught, survived, invalid, stale, timeout
    caught_by: list[str] = field(default_factory=list)
    seconds: float = 0.0
    detail: str = ""
    failed: list[str] = field(default_factory=list)  # every failing test seen


# ------------------------------------------------------------------------------------------
# the list


def _str_list(where: str, value: Any) -> list[str]:
    if not isinstance(value, list) or not all(isinstance(v, str) for v in value):
        raise ListError(f"{where} must be a list of strings")
    return list(value)


def _commands(where: str, value: Any) -> list[list[str]]:
    if not isinstance(value, list):
        raise ListError(f"{where} must be a list of commands (lists of strings)")
    return [_str_list(f"{where}[{i}]", c) for i, c in enumerate(value)]


def load_list(path: Path) -> tuple[Settings, list[Mutant]]:
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8"))
    except (OSError, tomllib.TOMLDecodeError) as exc:
        raise ListError(f"{path}: {exc}") from None
    unknown = set(data) - {"settings", "runners", "mutant"}
    if unknown:
        raise ListError(f"{path}: unknown table {sorted(unknown)[0]!r}")
    raw = data.get("settings", {})
    unknown = set(raw) - {"setup", "build", "timeout"}
    if unknown:
        raise ListError(f"{path}: [settings]: unknown key {sorted(unknown)[0]!r}")
    settings = Settings(
        setup=_commands("settings.setup", raw.get("setup", [])),
        build=_commands("settings.build", raw.get("build", [])),
        timeout=float(raw.get("timeout", 1800.0)),
    )
    for name, runner in data.get("runners", {}).items():
        if not isinstance(runner, dict) or set(runner) != {"command"}:
            raise ListError(f"{path}: [runners.{name}] must hold exactly `command`")
        settings.runners[name] = _str_list(f"runners.{name}.command", runner["command"])
    mutants: list[Mutant] = []
    allowed = {"name", "file", "search", "replace", "tests", "why", "each_layer"}
    for i, m in enumerate(data.get("mutant", [])):
        where = f"{path}: mutant {i + 1}"
        unknown = set(m) - allowed
        if unknown:
            raise ListError(f"{where}: unknown key {sorted(unknown)[0]!r}")
        for key in ("name", "file", "search", "replace"):
            if not isinstance(m.get(key), str) or not m[key]:
                raise ListError(f"{where}: `{key}` must be a non-empty string")
        where = f"{path}: mutant {m['name']!r}"
        if m["search"] == m["replace"]:
            raise ListError(f"{where}: search and replace are the same")
        tests = m.get("tests")
        if not isinstance(tests, dict) or not tests:
            raise ListError(f"{where}: `tests` must map runners to test lists")
        for runner, names in tests.items():
            if runner not in settings.runners:
                raise ListError(f"{where}: unknown runner {runner!r}")
            if not _str_list(f"{where}: tests.{runner}", names):
                raise ListError(f"{where}: tests.{runner} is empty")
        if any(x.name == m["name"] for x in mutants):
            raise ListError(f"{where}: the name is used twice")
        mutants.append(
            Mutant(
                name=m["name"],
                file=m["file"],
                search=m["search"],
                replace=m["replace"],
                tests={k: list(v) for k, v in tests.items()},
                why=str(m.get("why", "")),
                each_layer=bool(m.get("each_layer", False)),
            )
        )
    return settings, mutants


def applies(root: Path, mutant: Mutant) -> str:
    """'' if the mutant's search text occurs exactly once in its file, else why not."""
    path = root / mutant.file
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as exc:
        return f"{mutant.file}: {exc.strerror}"
    n = text.count(mutant.search)
    return "" if n == 1 else f"{mutant.file}: the search text occurs {n} times (must be once)"


# ------------------------------------------------------------------------------------------
# the scratch copy


def source_files(src: Path) -> list[str]:
    """The files of the working tree: what git tracks or would track (with their current
    contents), else every file outside build directories, caches and .git."""
    try:
        out = subprocess.run(
            ["git", "-C", str(src), "ls-files", "-z", "--cached", "--others", "--exclude-standard"],
            capture_output=True,
            check=True,
        ).stdout
        names = [n for n in out.decode().split("\0") if n]
        return sorted(n for n in names if (src / n).is_file() or (src / n).is_symlink())
    except (OSError, subprocess.CalledProcessError):
        names = []
        for dirpath, dirnames, filenames in os.walk(src):
            dirnames[:] = [
                d for d in dirnames if d not in SKIPPED_DIRS and not d.startswith("build")
            ]
            for f in filenames:
                names.append(str((Path(dirpath) / f).relative_to(src)))
        return sorted(names)


def sync_copy(src: Path, dst: Path) -> int:
    """Copy the working tree into dst, rewriting only the files whose contents differ (so that
    a kept build stays incremental). Returns the number of files written."""
    written = 0
    for name in source_files(src):
        a, b = src / name, dst / name
        if a.is_symlink():
            if b.is_symlink() and os.readlink(a) == os.readlink(b):
                continue
            b.parent.mkdir(parents=True, exist_ok=True)
            if b.exists() or b.is_symlink():
                b.unlink()
            os.symlink(os.readlink(a), b)
            written += 1
            continue
        data = a.read_bytes()
        if b.is_file() and not b.is_symlink() and b.read_bytes() == data:
            continue
        b.parent.mkdir(parents=True, exist_ok=True)
        if b.is_symlink():
            b.unlink()
        b.write_bytes(data)
        shutil.copymode(a, b)
        written += 1
    return written


@contextmanager
def mutated(root: Path, mutant: Mutant) -> Iterator[None]:
    """The mutant applied to the copy under root, and the file restored afterwards, whatever
    happens. The file's time stamp moves forward both times, so that incremental builds see
    the change."""
    path = root / mutant.file
    original = path.read_bytes()
    text = original.decode("utf-8")
    try:
        path.write_text(text.replace(mutant.search, mutant.replace, 1), encoding="utf-8")
        _touch_forward(path)
        yield
    finally:
        path.write_bytes(original)
        _touch_forward(path)


def _touch_forward(path: Path) -> None:
    now = time.time()
    st = path.stat()
    stamp = max(now, st.st_mtime + 1e-3)
    os.utime(path, (stamp, stamp))


# ------------------------------------------------------------------------------------------
# commands


@dataclass
class Result:
    returncode: int | None  # None: timed out
    output: str
    seconds: float


def run_command(argv: Sequence[str], cwd: Path, env: dict[str, str], timeout: float) -> Result:
    """Run one command in its own process group; on a timeout or an interruption the whole
    group (the command and its children) is killed before returning or raising."""
    start = time.monotonic()
    proc = subprocess.Popen(
        list(argv),
        cwd=cwd,
        env=env,
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        start_new_session=True,
    )
    try:
        out, _ = proc.communicate(timeout=timeout)
        return Result(proc.returncode, out.decode(errors="replace"), time.monotonic() - start)
    except subprocess.TimeoutExpired:
        _kill_group(proc)
        out, _ = proc.communicate()
        return Result(None, out.decode(errors="replace"), time.monotonic() - start)
    except BaseException:
        _kill_group(proc)
        proc.communicate()
        raise


def _kill_group(proc: subprocess.Popen[bytes]) -> None:
    try:
        os.killpg(proc.pid, signal.SIGKILL)  # the group this tool started, by its id
    except ProcessLookupError:
        pass


def expand(
    argv: Sequence[str], python: str, jobs: int, source: Path, tests: Sequence[str] = ()
) -> list[str]:
    regex = "^(" + "|".join(re.escape(t) for t in tests) + ")$"
    out: list[str] = []
    for arg in argv:
        if arg == "{tests}":
            out.extend(tests)
            continue
        for key, value in (
            ("{python}", python),
            ("{jobs}", str(jobs)),
            ("{regex}", regex),
            ("{source}", str(source)),
        ):
            arg = arg.replace(key, value)
        out.append(arg)
    return out


FAILED_PATTERNS = (
    re.compile(r"^FAILED (\S+)", re.M),  # pytest -q
    re.compile(r"^ERROR (\S+)", re.M),  # pytest: an error in a fixture or at collection
    re.compile(
        r"^\s*\d+ - (\S+) \((?:Failed|SEGFAULT|Subprocess aborted|Timeout|Child aborted|"
        r"Exception|OTHER_FAULT|Not Run)\)",
        re.M,
    ),  # ctest
)


def failed_tests(output: str) -> list[str]:
    names: list[str] = []
    for pattern in FAILED_PATTERNS:
        names += [m.group(1) for m in pattern.finditer(output)]
    return names


# ------------------------------------------------------------------------------------------
# the run


class Runner:
    def __init__(
        self,
        settings: Settings,
        source: Path,
        work: Path,
        jobs: int,
        timeout: float,
        log: Any = sys.stdout,
    ) -> None:
        self.settings = settings
        self.source = source
        self.work = work
        self.jobs = jobs
        self.timeout = timeout
        self.log = log
        env = dict(os.environ)
        for name in ENV_DROPPED:
            env.pop(name, None)
        env["PYTHONPATH"] = str(work / "python")
        env["PYTHONDONTWRITEBYTECODE"] = "1"
        self.env = env

    def say(self, text: str) -> None:
        print(text, file=self.log, flush=True)

    def commands(self, commands: list[list[str]], what: str) -> Result | None:
        """Run set-up or build commands; None on success, else the failing result."""
        for argv in commands:
            r = run_command(
                expand(argv, sys.executable, self.jobs, self.source),
                self.work,
                self.env,
                self.timeout,
            )
            if r.returncode != 0:
                return r
        return None

    def tests(self, runner: str, tests: Sequence[str]) -> Result:
        argv = expand(self.settings.runners[runner], sys.executable, self.jobs, self.source, tests)
        return run_command(argv, self.work, self.env, self.timeout)

    def baseline(self, mutants: Sequence[Mutant]) -> bool:
        union: dict[str, list[str]] = {}
        for m in mutants:
            for runner, names in m.tests.items():
                union.setdefault(runner, [])
                union[runner] += [n for n in names if n not in union[runner]]
        ok = True
        for runner, names in union.items():
            r = self.tests(runner, names)
            if r.returncode != 0:
                ok = False
                self.say(
                    f"baseline: the {runner} tests fail without any mutant "
                    f"({', '.join(failed_tests(r.output)) or 'see below'}):"
                )
                self.say(_tail(r.output))
            else:
                self.say(
                    f"baseline: {len(names)} {runner} test selections pass ({r.seconds:.0f} s)"
                )
        return ok

    def mutant(self, m: Mutant) -> Outcome:
        start = time.monotonic()
        why_not = applies(self.work, m)
        if why_not:
            return Outcome("stale", detail=why_not)
        with mutated(self.work, m):
            failed = self.commands(self.settings.build, "build")
            if failed is not None:
                status = "invalid" if failed.returncode is not None else "timeout"
                return Outcome(
                    status,
                    seconds=time.monotonic() - start,
                    detail="the build fails: " + _tail(failed.output, 6),
                )
            caught: list[str] = []
            failed: list[str] = []
            timed_out = False
            missed: list[str] = []
            for runner, names in m.tests.items():
                r = self.tests(runner, names)
                if r.returncode is None:
                    timed_out = True
                    caught.append(f"{runner} (timeout)")
                elif r.returncode != 0:
                    which = failed_tests(r.output)
                    failed += which
                    more = f" and {len(which) - 3} more" if len(which) > 3 else ""
                    caught.append(f"{runner} ({', '.join(which[:3]) or 'failed'}{more})")
                else:
                    missed.append(runner)
                if caught and not m.each_layer:
                    break
        seconds = time.monotonic() - start
        if missed and (m.each_layer or not caught):
            detail = f"not caught by {', '.join(missed)}"
            return Outcome("survived", caught, seconds, detail, failed)
        return Outcome("timeout" if timed_out else "caught", caught, seconds, failed=failed)


def _tail(text: str, lines: int = 25) -> str:
    return "\n".join("    " + line for line in text.strip().splitlines()[-lines:])


def report(mutants: Sequence[Mutant], outcomes: dict[str, Outcome]) -> str:
    rows = ["| mutant | file | status | caught by | s |", "|---|---|---|---|---|"]
    for m in mutants:
        o = outcomes.get(m.name)
        if o is None:
            continue
        by = "; ".join([*o.caught_by, *([o.detail] if o.detail else [])])
        rows.append(f"| {m.name} | {m.file} | {o.status} | {by} | {o.seconds:.0f} |")
    counts: dict[str, int] = {}
    for o in outcomes.values():
        counts[o.status] = counts.get(o.status, 0) + 1
    summary = ", ".join(f"{n} {s}" for s, n in sorted(counts.items()))
    return "\n".join(rows) + f"\n\n{len(outcomes)} mutants: {summary}"


def _raise_interrupted(signum: int, _frame: Any) -> None:
    raise Interrupted(signal.Signals(signum).name)


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="tools/mutants.py",
        description="Apply the mutants of a list one at a time to a copy of the sources, "
        "rebuild, run their tests, report the survivors (see the module docstring).",
    )
    parser.add_argument(
        "--list-file",
        type=Path,
        default=DEFAULT_LIST,
        help="the mutant list (default: tools/mutants.toml)",
    )
    parser.add_argument(
        "--source",
        type=Path,
        default=ROOT,
        help="the source tree (default: this repository's working tree)",
    )
    parser.add_argument(
        "--only",
        nargs="+",
        metavar="PATTERN",
        help="only the mutants whose names match one of these patterns",
    )
    parser.add_argument("--list", action="store_true", help="print the mutants and exit")
    parser.add_argument(
        "--check",
        action="store_true",
        help="check that every mutant applies to the sources, and exit",
    )
    parser.add_argument(
        "--workdir", type=Path, help="keep the copy and its build here (reused by the next run)"
    )
    parser.add_argument("--keep", action="store_true", help="keep the scratch copy")
    parser.add_argument(
        "--no-baseline",
        action="store_true",
        help="skip running the chosen tests on the unmodified copy first",
    )
    parser.add_argument("--jobs", type=int, default=2, help="build parallelism (default 2)")
    parser.add_argument(
        "--timeout", type=float, help="s per command (default: the list's, else 1800)"
    )
    parser.add_argument("--json", type=Path, help="also write the outcomes as JSON here")
    args = parser.parse_args(argv)

    try:
        settings, mutants = load_list(args.list_file)
    except ListError as exc:
        print(f"tools/mutants.py: {exc}", file=sys.stderr)
        return 2
    if args.only:
        mutants = [m for m in mutants if any(fnmatch.fnmatch(m.name, p) for p in args.only)]
        if not mutants:
            print(f"tools/mutants.py: no mutant matches {' '.join(args.only)}", file=sys.stderr)
            return 2
    src = args.source.resolve()
    if args.list:
        for m in mutants:
            layers = " and ".join(m.tests) if m.each_layer else " or ".join(m.tests)
            print(f"{m.name:40s} {m.file}  [{layers}]  {m.why}")
        return 0
    if args.check:
        bad = [(m, applies(src, m)) for m in mutants]
        bad = [(m, why) for m, why in bad if why]
        for m, why in bad:
            print(f"stale: {m.name}: {why}")
        print(f"{len(mutants) - len(bad)} of {len(mutants)} mutants apply to {src}")
        return 1 if bad else 0

    old_handlers = {
        s: signal.signal(s, _raise_interrupted) for s in (signal.SIGINT, signal.SIGTERM)
    }
    work = (
        args.workdir.resolve() if args.workdir else Path(tempfile.mkdtemp(prefix="csfh-mutants-"))
    )
    remove = args.workdir is None and not args.keep
    outcomes: dict[str, Outcome] = {}
    status = 0
    try:
        work.mkdir(parents=True, exist_ok=True)
        runner = Runner(settings, src, work, args.jobs, args.timeout or settings.timeout)
        n = sync_copy(src, work)
        runner.say(f"copy of {src} in {work} ({n} files written)")
        failed = runner.commands(settings.setup, "setup") or runner.commands(
            settings.build, "build"
        )
        if failed is not None:
            runner.say("the unmodified copy does not set up or build:\n" + _tail(failed.output))
            return 2
        if not args.no_baseline and not runner.baseline(mutants):
            return 2
        for i, m in enumerate(mutants, 1):
            o = runner.mutant(m)
            outcomes[m.name] = o
            by = "; ".join([*o.caught_by, *([o.detail] if o.detail else [])])
            runner.say(f"[{i}/{len(mutants)}] {m.name}: {o.status} {by} ({o.seconds:.0f} s)")
        print()
        print(report(mutants, outcomes))
        bad = [name for name, o in outcomes.items() if o.status in ("survived", "invalid", "stale")]
        status = 1 if bad else 0
    except Interrupted as exc:
        print(
            f"\ntools/mutants.py: interrupted ({exc}); the sources were never touched",
            file=sys.stderr,
        )
        if outcomes:
            print(report(mutants, outcomes), file=sys.stderr)
        status = 130
    finally:
        for s, h in old_handlers.items():
            signal.signal(s, h)
        if remove:
            shutil.rmtree(work, ignore_errors=True)
        elif work.exists():
            print(f"the copy is kept in {work}")
    if args.json and outcomes:
        args.json.write_text(
            json.dumps({k: vars(v) for k, v in outcomes.items()}, indent=2) + "\n",
            encoding="utf-8",
        )
    return status


if __name__ == "__main__":
    sys.exit(main())
