"""Scenes are data: a TOML file names the initial state, the stop time, the preset, which parts of
the model are on, parameter overrides, constant inputs and integrator settings (the keys below).

A scene is refused when it is loaded, with one line naming the file, the key and the value, when
it leaves these limits (so that no scene exhausts the memory or runs for hours by accident; the
run-length limits, csfh.model.limits, and the defaults of the keys are the [harness] and
[default_experiment] tables of modelDescription/variables.toml):

* ``name``: one plain file name (it names the output directory results/NAME): no ``/`` or
  backslash, not starting with ``.``, no control characters, at most 100 characters;
* ``stop_time`` <= ``MAX_STOP_TIME`` s (every transient of the hinge decays within seconds);
* ``output_interval`` <= ``stop_time``, and at most ``MAX_OUTPUT_SAMPLES`` output samples
  (``stop_time / output_interval``: each is a row of the tables);
* ``moreau_h`` <= ``stop_time`` (at least one step), and at most ``MAX_MOREAU_STEPS`` Moreau
  steps (``stop_time / moreau_h``);
* ``rtol`` in [1e-14, 1) (tighter than 1e-14 cannot be met in double precision);
* the initial state: speeds ``|vx|``, ``|vy|`` <= 100 m/s and ``|omega|`` <= 1000 rad/s (the
  contact laws are quasi-static: they hold for impact speeds far below these), ``|theta|`` <= pi,
  and a start in contact at most as deep as ``contact.max_initial_indentation`` (the FMU's
  check) and 1 % of ``contact.R1`` (Hertz contact assumes indentations small against the radii);
* every parameter and input as the FMU checks it (names, types, ranges, enumeration items: the
  generated interface, csfh.model.model_info), and the model's own checks (R1 < R2, v0 < v1,
  derived quantities finite) and the start's depth in the C core where it is built. Loading
  needs no binary; without the core, the FMU and the core make the model's checks and the
  contact.max_initial_indentation check when a run sets the model up, and only the 1 % of
  ``contact.R1`` limit is not checked.

    name = "csfh"
    description = "..."
    preset = "paper"            # or "consistent" (docs/model.md §9)
    stop_time = 1.0             # s (default: [default_experiment] stopTime)
    models = ["LN_spheres", "LN_cylinders", "LN_ESDU", "Moreau"]   # for `csfh compare`

    [initial]
    q = [0.01, 0.01, 0.0]       # x [m], y [m], theta [rad] of G1 relative to O2
    u = [0.0, 0.0, 0.0]         # vx [m/s], vy [m/s], omega [rad/s]

    [parts]
    flexure = true              # false: the flexure is never evaluated
    friction = true             # false: the friction law is never evaluated

    [parameters]                # any FMU parameter by name (enumerations by item name)
    "contact.cr" = 0.9

    [inputs]                    # constant inputs
    "F_ext[1]" = 0.0            # also F_ext[2], M_ext, a_base[1], a_base[2] (frame acceleration)

    [integrator]
    rtol = 1e-6                 # CVODE's relative tolerance (event-driven models; default:
                                # [default_experiment] tolerance, the FMU's own default)
    output_interval = 1e-4      # s, rows of the output tables (default: [harness])
    moreau_h = 1e-5             # s, Moreau step (default: [harness])
    stick_rule = "paper"        # Moreau: "paper" (f_a decides) or "memory"; default from preset
    v_eps = 0.0                 # Moreau: restitution only for gamma_N < -v_eps
    g_tol = 0.0                 # Moreau: contact active when the gap <= g_tol

    [cosim]                     # co-simulation with the comb-drive actuator (`csfh cosim`);
                                # keys in csfh.model.cosim_section, ignored by the other commands
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, fields, replace
from importlib import resources
from pathlib import Path
from typing import Any

from ..errors import ParameterError, SceneError
from ..scenes import BUILTIN_SCENES
from . import model_info
from ._csfh_variables import (
    DEFAULT_STOP_TIME,
    DEFAULT_TOLERANCE,
    MOREAU_G_TOL,
    MOREAU_STEP,
    MOREAU_V_EPS,
    OUTPUT_INTERVAL,
)
from .cosim_section import parse_cosim
from .limits import check_horizon
from .presets import PRESETS
from .scene_files import locate, parse, read_text
from .values import number as _number

STICK_RULES = ("paper", "memory")

# the limits of a scene besides its length (module docstring; the run-length limits and their
# checks are csfh.model.limits)
MAX_NAME_LENGTH = 100
MIN_RTOL = 1e-14
"""The tightest relative tolerance of CVODE."""
MAX_SPEED = 100.0
"""m/s: the largest initial |vx|, |vy|."""
MAX_ANGULAR_SPEED = 1000.0
"""rad/s: the largest initial |omega|."""
MAX_ROTATION = math.pi
"""rad: the largest initial |theta|."""
MAX_INDENTATION_OVER_R1 = 0.01
"""The deepest start in contact, as a fraction of contact.R1 (besides the FMU's
contact.max_initial_indentation)."""


@dataclass(frozen=True)
class IntegratorSettings:
    """The ``[integrator]`` table of a scene.

    * ``rtol``: relative tolerance of CVODE for the event-driven models (model exchange and
      co-simulation).
    * ``output_interval``: s, spacing of the rows of the output tables (and the communication
      step of co-simulation runs).
    * ``moreau_h``: s, step of the Moreau stepper.
    * ``stick_rule``: Moreau, ``"paper"`` (f_a decides sticking) or ``"memory"``; None takes the
      preset's (docs/model.md §6.4).
    * ``v_eps``: m/s, Moreau applies restitution only for gamma_N < -v_eps (§6.1, §6.3).
    * ``g_tol``: m, Moreau treats the contact as active when the gap is <= g_tol.
    """

    rtol: float = DEFAULT_TOLERANCE
    output_interval: float = OUTPUT_INTERVAL
    moreau_h: float = MOREAU_STEP
    stick_rule: str | None = None
    v_eps: float = MOREAU_V_EPS
    g_tol: float = MOREAU_G_TOL


@dataclass(frozen=True)
class Scene:
    """A scenario: initial state, stop time, preset, parts, parameter overrides, inputs and
    integrator settings (the keys of a scene file, see the user guide). Build one with
    :func:`load_scene` or :func:`scene_from_dict`; it is immutable (:meth:`with_parameters`
    makes a modified copy).

    * ``q0``, ``u0``: initial x [m], y [m], theta [rad] of G1 relative to O2, and their rates.
    * ``flexure``, ``friction``: whether those parts of the model are on.
    * ``parameters``: FMU parameters by name, applied after the preset's.
    * ``inputs``: constant values of ``F_ext[1]``, ``F_ext[2]``, ``M_ext``, ``a_base[1]``,
      ``a_base[2]`` (the frame's acceleration, docs/model.md §14.1).
    * ``models``: the models of ``csfh compare`` on this scene.
    * ``cosim``: the raw ``[cosim]`` table (validated by :func:`cosimulate`).
    """

    name: str
    description: str = ""
    preset: str = "paper"
    stop_time: float = DEFAULT_STOP_TIME
    q0: tuple[float, float, float] = (0.0, 0.0, 0.0)
    u0: tuple[float, float, float] = (0.0, 0.0, 0.0)
    flexure: bool = True
    friction: bool = True
    parameters: dict[str, Any] = field(default_factory=dict)
    inputs: dict[str, float] = field(default_factory=dict)
    integrator: IntegratorSettings = field(default_factory=IntegratorSettings)
    models: tuple[str, ...] = model_info.PAPER_MODELS
    source: str = ""
    cosim: dict[str, Any] = field(default_factory=dict)  # [cosim], see csfh.model.cosim_section

    @property
    def x0(self) -> list[float]:
        """The six initial states [x, y, theta, vx, vy, omega]."""
        return [*self.q0, *self.u0]

    @property
    def stick_rule(self) -> str:
        """The Moreau stick rule in use: the scene's, else its preset's."""
        return self.integrator.stick_rule or PRESETS[self.preset].stick_rule

    def parameter_values(self, law: str | None = None) -> dict[str, float | int | bool]:
        """Every parameter the scene sets, in application order: preset, parts, overrides, and
        the contact law of the model (None: keep the scene's)."""
        values: dict[str, Any] = dict(PRESETS[self.preset].parameters)
        values["flexure.enabled"] = self.flexure
        values["friction.enabled"] = self.friction
        values.update(self.parameters)
        if law is not None and law != "Moreau":
            values["contact.law"] = law
        return {name: model_info.coerce(name, v) for name, v in values.items()}

    def with_parameters(self, **overrides: Any) -> Scene:
        """A copy with more parameter overrides; names with dots go through a dict:
        ``scene.with_parameters(**{"contact.cr": 0.8})``."""
        return replace(self, parameters={**self.parameters, **overrides})


_TOP_KEYS = {
    "name",
    "description",
    "preset",
    "stop_time",
    "initial",
    "parts",
    "parameters",
    "inputs",
    "integrator",
    "models",
    "cosim",
}
_INPUTS = ("F_ext[1]", "F_ext[2]", "M_ext", "a_base[1]", "a_base[2]")


def _table(where: str, value: Any, allowed: set[str] | None = None) -> dict[str, Any]:
    if not isinstance(value, dict):
        raise SceneError(f"{where} must be a table")
    if allowed is not None:
        unknown = sorted(set(value) - allowed)
        if unknown:
            raise SceneError(
                f"{where}: unknown key {unknown[0]!r} (allowed: {', '.join(sorted(allowed))})"
            )
    return value


def _vector3(where: str, value: Any) -> tuple[float, float, float]:
    if not isinstance(value, list) or len(value) != 3:
        raise SceneError(f"{where} must be a list of 3 numbers")
    a, b, c = (_number(f"{where}[{i}]", v) for i, v in enumerate(value))
    return (a, b, c)


def scene_from_dict(data: dict[str, Any], source: str = "<dict>") -> Scene:
    """Validate a parsed scene and build it; errors name the file and the key."""
    try:
        return _scene_from_dict(data, source)
    except SceneError as exc:
        raise SceneError(f"{source}: {exc}") from None


def _scene_from_dict(data: dict[str, Any], source: str) -> Scene:
    _table("scene", data, _TOP_KEYS)
    name = data.get("name", Path(source).stem)
    check_name(name)
    preset = data.get("preset", "paper")
    if preset not in PRESETS:
        raise SceneError(f"preset = {preset!r} is not one of {', '.join(PRESETS)}")
    stop_time = _number("stop_time", data.get("stop_time", DEFAULT_STOP_TIME), positive=True)
    initial = _table("[initial]", data.get("initial", {}), {"q", "u"})
    q0 = _vector3("initial.q", initial.get("q", [0.0, 0.0, 0.0]))
    u0 = _vector3("initial.u", initial.get("u", [0.0, 0.0, 0.0]))
    parts = _table("[parts]", data.get("parts", {}), {"flexure", "friction"})
    for key, value in parts.items():
        if not isinstance(value, bool):
            raise SceneError(f"parts.{key} = {value!r} must be true or false")
    parameters = _parameters(data.get("parameters", {}))
    inputs = _table("[inputs]", data.get("inputs", {}), set(_INPUTS))
    inputs = {k: _number(f"inputs.{k}", v) for k, v in inputs.items()}
    settings = _integrator(data.get("integrator", {}), stop_time)
    models = _models(data.get("models", list(model_info.PAPER_MODELS)))
    description = data.get("description", "")
    if not isinstance(description, str):
        raise SceneError("description must be a string")
    cosim = dict(_table("[cosim]", data.get("cosim", {})))
    if cosim:
        parse_cosim(cosim, inputs)  # co-simulation settings: one-line errors like the above
    scene = Scene(
        name=name,
        description=description,
        preset=preset,
        stop_time=stop_time,
        q0=q0,
        u0=u0,
        flexure=parts.get("flexure", True),
        friction=parts.get("friction", True),
        parameters=parameters,
        inputs=inputs,
        integrator=settings,
        models=models,
        source=source,
        cosim=cosim,
    )
    _check_initial(scene)
    _check_values(scene)
    _check_model(scene)
    return scene


def _parameters(table: Any) -> dict[str, Any]:
    """[parameters]: FMU parameters by name, of the right type (not the parts' switches)."""
    parameters = dict(_table("[parameters]", table))
    known = set(model_info.parameter_names())
    for key, value in parameters.items():
        if key not in known:
            raise SceneError(f"parameters: unknown parameter {key!r}")
        if key in ("flexure.enabled", "friction.enabled"):
            raise SceneError(f"parameters: set {key!r} with [parts]")
        try:
            model_info.coerce(key, value)
        except ValueError as exc:
            raise SceneError(f"parameters: {exc}") from None
    return parameters


def _integrator(table: Any, stop_time: float) -> IntegratorSettings:
    """[integrator], each key defaulting to IntegratorSettings', within the limits of a run up to
    `stop_time`."""
    integ = _table("[integrator]", table, {f.name for f in fields(IntegratorSettings)})
    default = IntegratorSettings()

    def number(key: str, **sign: bool) -> float:
        return _number(f"integrator.{key}", integ.get(key, getattr(default, key)), **sign)

    settings = IntegratorSettings(
        rtol=number("rtol", positive=True),
        output_interval=number("output_interval", positive=True),
        moreau_h=number("moreau_h", positive=True),
        stick_rule=integ.get("stick_rule"),
        v_eps=number("v_eps", nonnegative=True),
        g_tol=number("g_tol"),
    )
    if not MIN_RTOL <= settings.rtol < 1:
        raise SceneError(
            f"integrator.rtol = {settings.rtol!r} must be in [{MIN_RTOL:g}, 1) (tighter than "
            f"{MIN_RTOL:g} cannot be met in double precision)"
        )
    check_horizon(stop_time, settings.output_interval, settings.moreau_h)
    if settings.stick_rule is not None and settings.stick_rule not in STICK_RULES:
        raise SceneError(
            f"integrator.stick_rule = {settings.stick_rule!r} is not one of "
            f"{', '.join(STICK_RULES)}"
        )
    return settings


def _models(models: Any) -> tuple[str, ...]:
    if not isinstance(models, list) or not models:
        raise SceneError("models must be a non-empty list")
    for m in models:
        if m not in model_info.MODELS:
            raise SceneError(f"models: unknown model {m!r} (known: {', '.join(model_info.MODELS)})")
    return tuple(models)


def check_name(name: Any) -> str:
    """A scene name names its output directory (results/NAME): one plain file name."""
    if not isinstance(name, str) or not name:
        raise SceneError(f"name = {name!r} must be a non-empty string")
    bad = next((c for c in name if c in "/\\" or ord(c) < 32 or ord(c) == 127), None)
    if bad is not None or name.startswith(".") or len(name) > MAX_NAME_LENGTH:
        raise SceneError(
            f"name = {name!r} must be a plain file name (it names the output directory "
            f"results/NAME): no '/' or '\\', not starting with '.', no control characters, at "
            f"most {MAX_NAME_LENGTH} characters"
        )
    return name


def check_run_horizon(scene: Scene, stop_time: float, stop_key: str = "--stop-time") -> None:
    """The scene's limits on a horizon that an option (`stop_key`) changed: SceneError naming
    the scene's file, the option and the value."""
    try:
        check_horizon(
            stop_time,
            scene.integrator.output_interval,
            scene.integrator.moreau_h,
            stop_key=stop_key,
        )
    except SceneError as exc:
        raise SceneError(f"{scene.source or scene.name}: {exc}") from None


def _check_initial(scene: Scene) -> None:
    theta = scene.q0[2]
    vx, vy, omega = scene.u0
    if not abs(theta) <= MAX_ROTATION:
        raise SceneError(
            f"initial.q[2] = {theta!r} rad: |theta| must be at most pi (the body's rotation from "
            "the reference)"
        )
    for key, value in (("initial.u[0]", vx), ("initial.u[1]", vy)):
        if not abs(value) <= MAX_SPEED:
            raise SceneError(
                f"{key} = {value!r} m/s: an initial speed must be at most {MAX_SPEED:g} m/s (the "
                "contact laws are quasi-static: they hold for impact speeds far below this)"
            )
    if not abs(omega) <= MAX_ANGULAR_SPEED:
        raise SceneError(
            f"initial.u[2] = {omega!r} rad/s: |omega| must be at most {MAX_ANGULAR_SPEED:g} rad/s"
        )


def _check_values(scene: Scene) -> None:
    """Every value the scene sets, as the FMU checks it (its range, an enumeration's items), from
    the generated interface: no binary needed."""
    for table, values in (("parameters", scene.parameter_values()), ("inputs", scene.inputs)):
        for name, value in values.items():
            try:
                model_info.check(name, value)
            except ParameterError as exc:
                raise SceneError(f"{table}: {exc}") from None


def _check_model(scene: Scene) -> None:
    """The model's own checks in the C core: R1 < R2, v0 < v1, the derived quantities finite, how
    deep the start is in the bore. Without a built core (a source checkout with no build) they
    wait for the run, where the FMU and the core make the same checks (but for the harness's
    limit of 1 % of contact.R1)."""
    from .core import CoreModel

    try:
        model = CoreModel()
    except FileNotFoundError:
        return
    try:
        for name, value in scene.parameter_values().items():
            model.set(name, value)
        model.prepare()
    except ParameterError as exc:
        raise SceneError(f"parameters: {exc}") from None
    # the FMU refuses a start deeper in the bore than contact.max_initial_indentation
    import numpy as np

    model.state = np.array(scene.x0)
    depth, limit = -model.get("contact.gap"), model.get("contact.max_initial_indentation")
    if depth > limit:
        raise SceneError(
            f"initial.q = {list(scene.q0)} is {depth:.6g} m deep in the bore (indentation "
            f"{depth:.6g} m > contact.max_initial_indentation = {limit:g} m)"
        )
    radius = model.get("contact.R1")
    if depth > MAX_INDENTATION_OVER_R1 * radius:
        raise SceneError(
            f"initial.q = {list(scene.q0)} is {depth:.6g} m deep in the bore: at most "
            f"{MAX_INDENTATION_OVER_R1:g} contact.R1 = {MAX_INDENTATION_OVER_R1 * radius:g} m "
            "(Hertz contact assumes indentations small against the radii)"
        )


def load_scene(scene: str | Path) -> Scene:
    """A built-in scene by name (csfh.scenes.BUILTIN_SCENES: ``central``, ``csfh``, ...) or a
    scene file by path. Raises :class:`SceneError` with a one-line message naming the file, the
    key and the value when the scene cannot be used."""
    path = locate(scene, BUILTIN_SCENES)
    if path is None:
        text = resources.files("csfh").joinpath("scenes", f"{scene}.toml").read_text("utf-8")
        source = f"{scene} (built-in)"
    else:
        text, source = read_text(path), str(path)
    return scene_from_dict(parse(text, source), source)
