"""Monte Carlo over manufacturing tolerances: the spread of the first-contact time, the peak
normal force and the peak friction force.

A tolerance file is a scene file with two more tables:

    [tolerance]                              # FMU parameter = distribution about its nominal
    "contact.R1" = {sigma = 2e-5}            # normal, standard deviation in SI units (m)
    "flexure.beta" = {sigma = 8.7e-4}        # rad
    "flexure.b" = {half_width = 5e-5}        # uniform in nominal +- half_width
    "body1.m" = {sigma = 0.01, mean = 10.0}  # optional mean (default: the scene's value)

    [montecarlo]                             # all optional; the command line overrides
    runs = 500
    seed = 1
    models = ["LN_cylinders", "Moreau"]

Sample k of every run uses its own generator numpy.random.default_rng([seed, k]) and draws the
parameters in sorted name order, so the samples depend on neither the number of runs nor the
executor, and every model sees the same sample k (common random numbers)."""

from __future__ import annotations

import math
import tomllib
from collections.abc import Sequence
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np

from ...batch.store import ResultStore
from ...batch.tasks import Task
from ...errors import ParameterError, SceneError
from ...model import model_info
from ...model.instance import core_model, nominal_values
from ...model.limits import MAX_RUNS, check_count
from ...model.scene import Scene, scene_from_dict
from ...model.scene_files import locate, parse, read_text
from ...model.values import as_float, shown

DEFAULT_FILE = "tolerance_csfh"
RUNS_WHAT = "Monte Carlo samples per model (csfh.model.limits)"
QUANTITIES = ("first_contact", "peak_F_N", "peak_abs_F_T")
LABELS = {
    "first_contact": ("first-contact time", "ms", 1e3),
    "peak_F_N": ("peak normal force F_N", "kN", 1e-3),
    "peak_abs_F_T": ("peak friction force (abs F_T)", "kN", 1e-3),
}


class ToleranceError(SceneError):
    """A tolerance file that cannot be used; the message names the key."""


@dataclass(frozen=True)
class Distribution:
    kind: str  # "normal" or "uniform"
    width: float  # sigma or half width, SI
    mean: float | None = None  # None: the scene's nominal value

    def describe(self, unit: str = "") -> str:
        u = f" {unit}" if unit else ""
        base = "nominal" if self.mean is None else f"{self.mean:g}{u}"
        if self.kind == "normal":
            return f"normal, mean {base}, σ = {self.width:g}{u}"
        return f"uniform, {base} ± {self.width:g}{u}"


@dataclass(frozen=True)
class ToleranceStudy:
    scene: Scene
    tolerances: dict[str, Distribution]
    runs: int = 200
    seed: int = 1
    models: tuple[str, ...] = model_info.PAPER_MODELS
    source: str = ""
    nominal: dict[str, float] = field(default_factory=dict)


def _finite(value: Any) -> bool:
    """A finite number (not a boolean; not an integer beyond the doubles)."""
    return (
        not isinstance(value, bool)
        and isinstance(value, int | float)
        and math.isfinite(as_float(value))
    )


def _parse_distribution(key: str, spec: Any) -> Distribution:
    where = f"tolerance.{key!r}"
    if not isinstance(spec, dict):
        raise ToleranceError(f"{where} must be a table such as {{sigma = 1e-5}}")
    unknown = sorted(set(spec) - {"sigma", "half_width", "mean"})
    if unknown:
        raise ToleranceError(
            f"{where}: unknown key {unknown[0]!r} (allowed: half_width, mean, sigma)"
        )
    kinds = [k for k in ("sigma", "half_width") if k in spec]
    if len(kinds) != 1:
        raise ToleranceError(f"{where} needs exactly one of sigma (normal) or half_width (uniform)")
    width = spec[kinds[0]]
    if not _finite(width) or width <= 0:
        raise ToleranceError(f"{where}: {kinds[0]} = {shown(width)} must be a number > 0")
    mean = spec.get("mean")
    if mean is not None and not _finite(mean):
        raise ToleranceError(f"{where}: mean = {shown(mean)} must be a finite number")
    return Distribution(
        "normal" if kinds[0] == "sigma" else "uniform",
        float(width),
        None if mean is None else float(mean),
    )


def _int_option(where: str, value: Any, minimum: int) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or value < minimum:
        raise ToleranceError(f"{where} = {shown(value)} must be an integer >= {minimum}")
    return value


def _parse_tolerances(tol: Any) -> dict[str, Distribution]:
    if not isinstance(tol, dict) or not tol:
        raise ToleranceError("[tolerance] must be a non-empty table")
    real = {
        n
        for n, v in model_info.variables().items()
        if v.causality == "parameter" and v.type == "Real"
    }
    tolerances = {}
    for key in sorted(tol):
        if key not in real:
            raise ToleranceError(f"tolerance: {key!r} is not a real FMU parameter")
        tolerances[key] = _parse_distribution(key, tol[key])
    return tolerances


def _parse_montecarlo(mc: Any) -> tuple[int, int]:
    """runs and seed of a [montecarlo] table (its models are checked by the caller)."""
    if not isinstance(mc, dict):
        raise ToleranceError("[montecarlo] must be a table")
    unknown = sorted(set(mc) - {"runs", "seed", "models"})
    if unknown:
        raise ToleranceError(
            f"[montecarlo]: unknown key {unknown[0]!r} (allowed: models, runs, seed)"
        )
    runs = _int_option("montecarlo.runs", mc.get("runs", 200), 1)
    try:
        check_count("montecarlo.runs", runs, MAX_RUNS, RUNS_WHAT)
    except ParameterError as exc:
        raise ToleranceError(str(exc)) from None
    seed = _int_option("montecarlo.seed", mc.get("seed", 1), 0)
    return runs, seed


def study_from_dict(data: dict[str, Any], source: str) -> ToleranceStudy:
    data = dict(data)
    tol = data.pop("tolerance", None)
    mc = data.pop("montecarlo", {})
    try:
        scene = scene_from_dict(data, source)
    except SceneError as exc:
        raise ToleranceError(str(exc)) from None
    try:
        if tol is None:
            tol = _default_tolerances()
            source = f"{source} (no [tolerance] table: the defaults of {DEFAULT_FILE})"
        tolerances = _parse_tolerances(tol)
        runs, seed = _parse_montecarlo(mc)
        models = mc.get("models", list(model_info.PAPER_MODELS))
        if not isinstance(models, list) or not models:
            raise ToleranceError("montecarlo.models must be a non-empty list")
        for m in models:
            if m not in model_info.MODELS:
                raise ToleranceError(f"montecarlo.models: unknown model {m!r}")
    except ToleranceError as exc:
        raise ToleranceError(f"{source}: {exc}") from None
    return ToleranceStudy(
        scene=scene,
        tolerances=tolerances,
        runs=runs,
        seed=seed,
        models=tuple(models),
        source=source,
        nominal=nominal_values(scene, list(tolerances)),
    )


def _builtin_text(name: str) -> str | None:
    ref = resources.files("csfh").joinpath("scenes", f"{name}.toml")
    return ref.read_text("utf-8") if ref.is_file() else None


def _default_tolerances() -> dict[str, Any]:
    text = _builtin_text(DEFAULT_FILE)
    assert text is not None, "the package lost its default tolerance file"
    return dict(tomllib.loads(text)["tolerance"])


def _builtin_names() -> list[str]:
    scenes = resources.files("csfh").joinpath("scenes")
    return [e.name.removesuffix(".toml") for e in scenes.iterdir() if e.name.endswith(".toml")]


def _read(arg: str | Path) -> tuple[dict[str, Any], str]:
    """The TOML of a tolerance file by path, or of a built-in scene by name, and its source
    (which file an argument names: csfh.model.scene_files)."""
    path = locate(arg, _builtin_names(), "tolerance", ToleranceError)
    if path is None:
        text, source = str(_builtin_text(str(arg))), f"{arg} (built-in)"
    else:
        text, source = read_text(path, ToleranceError), str(path)
    return parse(text, source, ToleranceError), source


def load_study(arg: str | Path) -> ToleranceStudy:
    """A tolerance file by path, or a built-in scene by name (tolerance_csfh, or any built-in
    scene, which then gets the default tolerances of tolerance_csfh)."""
    data, source = _read(arg)
    return study_from_dict(data, source)


def study_for_scene(scene: Scene, arg: str | Path) -> ToleranceStudy:
    """The [tolerance] and [montecarlo] tables (runs, seed) of a tolerance file (path, or a
    built-in name such as tolerance_csfh), applied to `scene`: the file's own scene keys, if it
    has any, are not used. The distributions' nominal values are `scene`'s."""
    data, source = _read(arg)
    try:
        if "tolerance" not in data:
            raise ToleranceError("no [tolerance] table")
        tolerances = _parse_tolerances(data["tolerance"])
        runs, seed = _parse_montecarlo(data.get("montecarlo", {}))
    except ToleranceError as exc:
        raise ToleranceError(f"{source}: {exc}") from None
    return ToleranceStudy(
        scene=scene,
        tolerances=tolerances,
        runs=runs,
        seed=seed,
        models=(),
        source=source,
        nominal=nominal_values(scene, list(tolerances)),
    )


def sample(study: ToleranceStudy, k: int) -> dict[str, float]:
    """Parameter values of run k (deterministic, see the module docstring)."""
    rng = np.random.default_rng([study.seed, k])
    values = {}
    for key in sorted(study.tolerances):
        d = study.tolerances[key]
        mean = study.nominal[key] if d.mean is None else d.mean
        if d.kind == "normal":
            values[key] = float(mean + d.width * rng.standard_normal())
        else:
            values[key] = float(mean + d.width * rng.uniform(-1.0, 1.0))
    return values


def check_samples(study: ToleranceStudy, samples: Sequence[dict[str, float]]) -> None:
    """Every sample must be a valid model (e.g. R1 < R2): the first invalid one is an error."""
    for k, values in enumerate(samples):
        try:
            core_model(study.scene, values)
        except ParameterError as exc:
            raise ToleranceError(
                f"{study.source}: run {k} draws an invalid model ({exc}); narrow the tolerances"
            ) from None


def tolerance_tasks(
    study: ToleranceStudy,
    samples: Sequence[dict[str, float]],
    stop_time: float,
    output_interval: float,
    interface: str,
) -> list[Task]:
    tasks = []
    for model in study.models:
        tasks.append(
            Task(
                scene=study.scene,
                model=model,
                stop_time=stop_time,
                output_interval=output_interval,
                interface=interface,
                signals=False,
                meta=(("run", -1),),
            )
        )
        for k, values in enumerate(samples):
            tasks.append(
                Task(
                    scene=study.scene,
                    model=model,
                    parameters=tuple(sorted(values.items())),
                    stop_time=stop_time,
                    output_interval=output_interval,
                    interface=interface,
                    signals=False,
                    meta=(("run", k),),
                )
            )
    return tasks


def _stats(v: np.ndarray) -> dict[str, Any]:
    v = v[np.isfinite(v)]
    if len(v) == 0:
        return {"n": 0}
    q = np.percentile(v, [1, 5, 50, 95, 99])
    return {
        "n": len(v),
        "mean": float(np.mean(v)),
        "std": float(np.std(v, ddof=1)) if len(v) > 1 else 0.0,
        "min": float(np.min(v)),
        "max": float(np.max(v)),
        "p01": float(q[0]),
        "p05": float(q[1]),
        "median": float(q[2]),
        "p95": float(q[3]),
        "p99": float(q[4]),
    }


def _correlations(X: np.ndarray, keys: list[str], values: dict[str, np.ndarray]) -> dict[str, Any]:
    """Per quantity, the Pearson correlation of each sampled parameter with it (None where
    either does not vary or fewer than three runs have it)."""
    corr: dict[str, dict[str, float | None]] = {}
    for q in QUANTITIES:
        corr[q] = {}
        y = values[q]
        ok = np.isfinite(y)
        for j, k in enumerate(keys):
            x = X[ok, j]
            if ok.sum() > 2 and np.std(x) > 0 and np.std(y[ok]) > 0:
                corr[q][k] = float(np.corrcoef(x, y[ok])[0, 1])
            else:
                corr[q][k] = None
    return corr


def _model(mt: list[Task], X: np.ndarray, keys: list[str], store: ResultStore) -> dict[str, Any]:
    """One model's nominal run, statistics, contact counts and correlations."""
    nominal = next(t for t in mt if dict(t.meta)["run"] == -1)
    runs = sorted((t for t in mt if dict(t.meta)["run"] >= 0), key=lambda t: dict(t.meta)["run"])
    values = {q: np.array([_num(store.summary(t.key)[q]) for t in runs]) for q in QUANTITIES}
    contacts = np.array([store.summary(t.key)["contacts"] for t in runs])
    return {
        "nominal": store.summary(nominal.key),
        "stats": {q: _stats(values[q]) for q in QUANTITIES},
        "no_contact_runs": int(np.sum(~np.isfinite(values["first_contact"]))),
        "contacts": _stats(contacts.astype(float)),
        "contacts_values": [int(c) for c in contacts],
        "correlation": _correlations(X, keys, values),
        "values": {
            q: [None if not math.isfinite(v) else float(v) for v in values[q]] for q in QUANTITIES
        },
    }


def analyse(
    study: ToleranceStudy,
    samples: Sequence[dict[str, float]],
    tasks: Sequence[Task],
    store: ResultStore,
) -> dict[str, Any]:
    keys = sorted(study.tolerances)
    X = np.array([[s[k] for k in keys] for s in samples]) if samples else np.zeros((0, len(keys)))
    out: dict[str, Any] = {"models": {}}
    for model in study.models:
        out["models"][model] = _model([t for t in tasks if t.model == model], X, keys, store)
    out["samples"] = {k: [s[k] for s in samples] for k in keys}
    out["sample_stats"] = {k: _stats(np.array([s[k] for s in samples])) for k in keys}
    return out


def _num(v: Any) -> float:
    return math.nan if v is None else float(v)
