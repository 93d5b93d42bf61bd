"""The FMU reproduces the recorded trajectories bit for bit (identity_runs.py says which).

A restructuring of the C code must not move a bit. Where a change must reorder floating-point
operations, list the run in REORDERED with the reason: it is then held to 1e-12 of each
quantity's scale at the sampled rows."""

from __future__ import annotations

import json
import os
from functools import cache

import identity_runs as ir
import numpy as np
import pytest

REORDERED: dict[str, str] = {}
"""Run key -> why its floating-point operations were reordered."""


@cache
def reference() -> tuple[dict, dict[str, np.ndarray]]:
    with np.load(ir.REFERENCE) as data:
        meta = json.loads(str(data["meta"]))
        rows = {key: data[key] for key in meta}
    return meta, rows


def fmu(version: int) -> str:
    env = os.environ.get("CSFH_FMU" if version == 2 else "CSFH_FMU3")
    if env:
        return env
    import csfh

    return str(csfh.fmu_path(fmi_version=version))


def test_the_reference_covers_every_run() -> None:
    meta, _ = reference()
    assert sorted(meta) == sorted(r.key for r in ir.runs())


@pytest.mark.parametrize("run", ir.runs(), ids=lambda r: r.key)
def test_trajectory_is_unchanged(run: ir.Run) -> None:
    meta, sampled = reference()
    expected = meta[run.key]
    names, data = ir.matrix(
        ir.simulate(fmu(run.fmi_version), run, expected["start"], expected["rtol"])
    )
    assert names == expected["names"]
    assert list(data.shape) == expected["shape"], "a different number of rows"
    if ir.digest(data) == expected["sha256"]:
        return
    scale = np.maximum(np.asarray(expected["scale"]), np.finfo(float).tiny)
    moved = np.abs(data[expected["rows"]] - sampled[run.key]) / scale
    worst = np.unravel_index(np.argmax(moved), moved.shape)
    where = f"{names[worst[1]]} at row {expected['rows'][worst[0]]}"
    if run.key in REORDERED:
        assert moved.max() <= 1e-12, f"moved by {moved.max():.3g} of its scale ({where})"
        return
    pytest.fail(f"not bitwise identical: up to {moved.max():.3g} of the scale ({where})")
