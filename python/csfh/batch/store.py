"""The result store of batched runs: per-task results in a directory, appended as they complete,
so that an interrupted command resumes where it stopped.

Layout (DIR): tasks.jsonl, one line per finished task
{"key", "model", "parameters", "summary", "signals"}; signals/KEY.npz with the output signals on
the grid (sweeps only). A line is appended (and fsync'ed) only after its signals are in place, so
an interrupted run leaves a consistent store; a torn last line is dropped on the next open."""

from __future__ import annotations

import json
import os
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from .tasks import Task


class ResultStore:
    """Per-task results in a directory, appended as they complete (see the module docstring)."""

    def __init__(self, directory: Path) -> None:
        self.directory = Path(directory)
        self.directory.mkdir(parents=True, exist_ok=True)
        self.index = self.directory / "tasks.jsonl"
        self.records: dict[str, dict[str, Any]] = {}
        self._load()

    def _load(self) -> None:
        if not self.index.exists():
            return
        data = self.index.read_bytes()
        good = 0
        for line in data.splitlines(keepends=True):
            if not line.endswith(b"\n"):
                break  # torn last line of an interrupted write
            try:
                rec = json.loads(line)
                key = rec["key"]
            except (ValueError, KeyError, TypeError):
                break
            if rec.get("signals") and not (self.directory / rec["signals"]).exists():
                break
            self.records[key] = rec
            good += len(line)
        if good != len(data):  # drop what cannot be read, so that appends stay line-aligned
            with open(self.index, "r+b") as fh:
                fh.truncate(good)

    def __contains__(self, key: str) -> bool:
        return key in self.records

    def __len__(self) -> int:
        return len(self.records)

    def add(
        self,
        task: Task,
        summary: dict[str, Any],
        signals: dict[str, np.ndarray] | None,
        wall_time: float = 0.0,
    ) -> None:
        self.add_many([(task, summary, signals, wall_time)])

    def add_many(
        self,
        results: Sequence[tuple[Task, dict[str, Any], dict[str, np.ndarray] | None, float]],
    ) -> None:
        """Store results: signal files first, then one index line each, one fsync for all."""
        lines, records = [], []
        for task, summary, signals, wall_time in results:
            rel = None
            if signals is not None:
                rel = f"signals/{task.key}.npz"
                (self.directory / "signals").mkdir(exist_ok=True)
                tmp = self.directory / f"signals/.{task.key}.tmp.npz"
                np.savez_compressed(tmp, **signals)
                os.replace(tmp, self.directory / rel)
            rec = {
                "key": task.key,
                "model": task.model,
                "parameters": dict(task.parameters),
                "stop_time": task.stop_time,
                "meta": dict(task.meta),
                "summary": summary,
                "signals": rel,
                "wall_time": wall_time,
            }
            lines.append(json.dumps(rec, sort_keys=True) + "\n")
            records.append(rec)
        if not lines:
            return
        with open(self.index, "a", encoding="utf-8") as fh:
            fh.write("".join(lines))
            fh.flush()
            os.fsync(fh.fileno())
        for rec in records:
            self.records[rec["key"]] = rec

    def summary(self, key: str) -> dict[str, Any]:
        return self.records[key]["summary"]

    def signals(self, key: str) -> dict[str, np.ndarray]:
        rel = self.records[key]["signals"]
        if rel is None:
            raise KeyError(f"task {key} has no signals")
        with np.load(self.directory / rel) as data:
            return {name: data[name] for name in data.files}
