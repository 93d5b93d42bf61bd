"""A design as a scene file: the study's scene with the design's parameter overrides, written as
TOML that csfh.model.scene.load_scene reads back to the same scene (every number as Python's
repr, which TOML reads back exactly)."""

from __future__ import annotations

import json
from dataclasses import fields
from typing import Any

from ...model.scene import IntegratorSettings, Scene


def _value(v: Any) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int | float):
        return repr(v) if isinstance(v, int) else repr(float(v))
    if isinstance(v, str):
        return json.dumps(v, ensure_ascii=False)
    if isinstance(v, list | tuple):
        return "[" + ", ".join(_value(x) for x in v) + "]"
    raise TypeError(f"no TOML form for {v!r}")


def _table(name: str, values: dict[str, Any]) -> list[str]:
    lines = ["", f"[{name}]"]
    lines += [f"{json.dumps(k)} = {_value(v)}" for k, v in values.items()]
    return lines


def scene_toml(
    scene: Scene, name: str, description: str, overrides: dict[str, float], header: str
) -> str:
    """The TOML text of `scene` named `name`, its parameters updated by `overrides`; `header`
    becomes the file's leading comment. The [cosim] table is not written (csfh shock and csfh
    design do not use it)."""
    lines = [f"# {line}" if line else "#" for line in header.splitlines()]
    lines += [
        f"name = {_value(name)}",
        f"description = {_value(description)}",
        f"preset = {_value(scene.preset)}",
        f"stop_time = {_value(scene.stop_time)}",
        f"models = {_value(list(scene.models))}",
    ]
    lines += _table("initial", {"q": list(scene.q0), "u": list(scene.u0)})
    lines += _table("parts", {"flexure": scene.flexure, "friction": scene.friction})
    lines += _table("parameters", {**scene.parameters, **overrides})
    if scene.inputs:
        lines += _table("inputs", dict(scene.inputs))
    integrator = {
        f.name: getattr(scene.integrator, f.name)
        for f in fields(IntegratorSettings)
        if getattr(scene.integrator, f.name) is not None
    }
    lines += _table("integrator", integrator)
    return "\n".join(lines) + "\n"
