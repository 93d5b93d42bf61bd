"""The coupled system of a scene as an SSP 1.0 archive (System Structure and Parameterization,
ssp-standard.org): `csfh cosim SCENE --export-ssp FILE`, `csfh.ssp_path("combdrive")`.

The archive (a zip, ``.ssp``) holds

* ``SystemStructure.ssd``: the system with two components, ``csfh`` (resources/csfh.fmu) and
  ``combdrive`` (resources/combdrive.fmu), their connectors (named and typed as in the FMUs'
  modelDescription.xml), the connections of csfh.cosim.coupling, the parameter values of the
  scene as inline ParameterBindings on each component, and the DefaultExperiment (start 0, the
  scene's stop time, the communication step as the Open Simulation Platform's FixedStepAlgorithm
  annotation, which libcosim reads);
* ``resources/csfh.fmu`` and ``resources/combdrive.fmu``: the FMUs of this build, byte for byte.

Two choices make the file complete for importers that only read SSP:

* the voltage ramp V(t) of the scene is the actuator FMU's own ramp.V0, ramp.V1, ramp.t0,
  ramp.t1 parameters (its input V left unconnected at 0): four parameters of the FMU that
  already drives the force, rather than a third FMU with its own build, interface and step;
* the hinge's start state is bound as initial.from_parameters = true and initial.body1.*
  (parameters), because libcosim's SSP loader applies values only to parameters and inputs,
  not to the start values of the states (outputs with initial="exact").

Enumeration parameters are bound through their Integer twins (contact.law_number, ...): libcosim
refuses Enumeration values in SSP. What SSP 1.0 cannot carry is refused with a SceneError:
a CVODE tolerance other than the FMU's default (fmi2SetupExperiment's, not a variable).

The importers differ in what they apply (read from their sources):

* libcosim (libcosimpy ``CosimExecution.from_ssp_file``): components, connections, the
  parameter bindings (inline or .ssv) and the fixed step of the annotation; fixed-step Jacobi
  with an exchange of the connected values at initialization, like ``csfh cosim``;
* fmpy (``fmpy.ssp.simulation.simulate_ssp``, FMI 1.0/2.0 co-simulation): components and
  connections, Jacobi, every connected input 0 over the first step; it parses the bindings
  but applies only a ParameterSet passed to it, and neither the step nor the stop time.
  `simulate_with_fmpy` passes the archive's bindings and its DefaultExperiment.
"""

from __future__ import annotations

import hashlib
import io
import os
import zipfile
from pathlib import Path
from typing import Any
from xml.etree import ElementTree as ET

import numpy as np

from .._version import __version__
from ..errors import ResultsError, SceneError
from ..model.cosim_section import CONNECTIONS, DEFAULT_TOLERANCE, CosimSettings
from ..model.fmus import description
from ..model.limits import check_horizon
from ..model.scene import Scene, load_scene
from ..output import write_bytes
from ..paths import combdrive_fmu_path, fmu_path
from ..runners.fmu import OUTPUT_NAMES, STATE_NAMES
from ..safepath import check_target
from .coupling import ACTUATOR_COLUMNS, CosimError, actuator_start_values, csfh_start_values

NS = {
    "ssd": "http://ssp-standard.org/SSP1/SystemStructureDescription",
    "ssc": "http://ssp-standard.org/SSP1/SystemStructureCommon",
    "ssv": "http://ssp-standard.org/SSP1/SystemStructureParameterValues",
    "osp": "http://opensimulationplatform.com/SSP/OSPAnnotations",
}
"""The namespaces, with the prefixes libcosim's parser requires literally (it matches
"ssd:Component", not the namespace)."""

SSD_NAME = "SystemStructure.ssd"
COMPONENTS = {"csfh": "resources/csfh.fmu", "combdrive": "resources/combdrive.fmu"}
"""Component name -> its FMU inside the archive."""
FMU_TYPE = "application/x-fmu-sharedlibrary"
OSP_ANNOTATION = "com.opensimulationplatform"
FORMAT = 1
"""Version of what this module writes (part of the cache key of `ssp_path`)."""

for _prefix, _uri in NS.items():
    ET.register_namespace(_prefix, _uri)


def _q(tag: str) -> str:
    prefix, name = tag.split(":")
    return f"{{{NS[prefix]}}}{name}"


def _text(var: Any, value: Any) -> str:
    """An SSV value attribute: xs:double with all digits, xs:int, xs:boolean."""
    if var.type == "Real":
        return repr(float(value))
    if var.type == "Boolean":
        return "true" if bool(value) else "false"
    return str(int(value))


def _bindable(md: Any, values: dict[str, Any], where: str) -> dict[str, tuple[Any, Any]]:
    """name -> (variable, value) for a ParameterSet: Enumerations through their Integer twin
    (name_number); an Enumeration without a twin only at its start value (then left out)."""
    variables = {v.name: v for v in md.modelVariables}
    out: dict[str, tuple[Any, Any]] = {}
    for name, value in values.items():
        var = variables.get(name)
        if var is None:
            raise SceneError(f"{where}: {name} is not a variable of {md.modelName}")
        if var.type == "Enumeration":
            twin = variables.get(f"{name}_number")
            if twin is not None and twin.type == "Integer":
                out[twin.name] = (twin, int(value))
            elif int(value) != int(var.start):
                raise SceneError(
                    f"{where}: {name} = {value} is an Enumeration without an Integer twin; "
                    "SSP importers (libcosim) cannot set it"
                )
            continue
        out[name] = (var, value)
    return out


def _typed(parent: ET.Element, tag: str, var: Any, value: Any | None = None) -> None:
    """The type element (ssc:Real for a connector, ssv:Real value=... for a parameter)."""
    element = ET.SubElement(parent, _q(f"{tag}:{var.type}"))
    if value is not None:
        element.set("value", _text(var, value))


def _component(
    system_elements: ET.Element,
    name: str,
    md: Any,
    connectors: list[tuple[str, str]],
    parameters: dict[str, tuple[Any, Any]],
) -> None:
    variables = {v.name: v for v in md.modelVariables}
    comp = ET.SubElement(
        system_elements,
        _q("ssd:Component"),
        {
            "name": name,
            "source": COMPONENTS[name],
            "type": FMU_TYPE,
            "implementation": "CoSimulation",
        },
    )
    conns = ET.SubElement(comp, _q("ssd:Connectors"))
    for var_name, kind in [*connectors, *((n, "parameter") for n in parameters)]:
        var = variables[var_name]
        if var.causality != kind:  # SSP 1.0: the kind must match the FMI 2.0 causality
            raise CosimError(f"{name}.{var_name} has causality {var.causality}, not {kind}")
        c = ET.SubElement(conns, _q("ssd:Connector"), {"name": var_name, "kind": kind})
        _typed(c, "ssc", var)
    bindings = ET.SubElement(comp, _q("ssd:ParameterBindings"))
    binding = ET.SubElement(bindings, _q("ssd:ParameterBinding"))
    values = ET.SubElement(binding, _q("ssd:ParameterValues"))
    pset = ET.SubElement(values, _q("ssv:ParameterSet"), {"version": "1.0", "name": name})
    plist = ET.SubElement(pset, _q("ssv:Parameters"))
    for var_name, (var, value) in parameters.items():
        p = ET.SubElement(plist, _q("ssv:Parameter"), {"name": var_name})
        _typed(p, "ssv", var, value)


def _hinge(
    scene: Scene, csfh_md: Any, where: str
) -> tuple[dict[str, Any], dict[str, Any], set[str]]:
    """The hinge's start values (its parameters and constant inputs, the start state as the
    initial.* parameters), those SSP binds as parameters, and the constant inputs among them."""
    start = csfh_start_values(scene)
    hinge = {k: v for k, v in start.items() if k not in STATE_NAMES}
    hinge["initial.from_parameters"] = True
    hinge.update({f"initial.{n}": float(start[n]) for n in STATE_NAMES})
    params = _bindable(csfh_md, hinge, where)
    bound_inputs = {n for n, (var, _) in params.items() if var.causality == "input"}
    return hinge, {n: pv for n, pv in params.items() if n not in bound_inputs}, bound_inputs


def _bind_inputs(component: Any, names: set[str], csfh_md: Any, hinge: dict[str, Any]) -> None:
    """Constant inputs of the scene (not connected): bound like parameters, as SSP allows."""
    if not names:
        return
    variables = {v.name: v for v in csfh_md.modelVariables}
    plist = component.find(
        "ssd:ParameterBindings/ssd:ParameterBinding/ssd:ParameterValues/"
        "ssv:ParameterSet/ssv:Parameters",
        NS,
    )
    assert plist is not None
    for n in sorted(names):
        p = ET.SubElement(plist, _q("ssv:Parameter"), {"name": n})
        _typed(p, "ssv", variables[n], hinge[n])


def _connections(system: Any, links: list[tuple[str, str]], moment: bool) -> None:
    """The actuator's outputs to the hinge's inputs, and theta back with the moment."""
    wires = [("combdrive", out, "csfh", inp) for out, inp in links]
    if moment:
        wires.append(("csfh", "body1.theta", "combdrive", "theta"))
    connections = ET.SubElement(system, _q("ssd:Connections"))
    for start_element, start_connector, end_element, end_connector in wires:
        ET.SubElement(
            connections,
            _q("ssd:Connection"),
            {
                "startElement": start_element,
                "startConnector": start_connector,
                "endElement": end_element,
                "endConnector": end_connector,
            },
        )


def _experiment(root: Any, stop_time: float, step: float) -> None:
    """The default experiment, with OSP's fixed-step algorithm annotation."""
    experiment = ET.SubElement(
        root, _q("ssd:DefaultExperiment"), {"startTime": "0.0", "stopTime": repr(stop_time)}
    )
    annotations = ET.SubElement(experiment, _q("ssd:Annotations"))
    annotation = ET.SubElement(annotations, _q("ssc:Annotation"), {"type": OSP_ANNOTATION})
    algorithm = ET.SubElement(annotation, _q("osp:Algorithm"))
    ET.SubElement(algorithm, _q("osp:FixedStepAlgorithm"), {"baseStepSize": repr(step)})


def _check_tolerance(s: CosimSettings, where: str) -> None:
    if s.tolerance is not None and s.tolerance != DEFAULT_TOLERANCE:
        raise SceneError(
            f"{where}: cosim.tolerance = {s.tolerance!r} cannot be carried by SSP 1.0 (it is "
            f"fmi2SetupExperiment's, not a variable; importers use the FMU's default "
            f"{DEFAULT_TOLERANCE:g}): remove the key to export"
        )


def ssd_text(
    scene: Scene,
    settings: CosimSettings,
    stop_time: float,
    csfh_md: Any,
    actuator_md: Any,
) -> str:
    """SystemStructure.ssd of the scene's coupled system (see the module's docstring)."""
    s = settings
    where = scene.source or scene.name
    _check_tolerance(s, where)
    links = [(o, i) for o, i in CONNECTIONS if s.moment or o != "M"]
    hinge, csfh_params, bound_inputs = _hinge(scene, csfh_md, where)
    csfh_connectors = [(i, "input") for _, i in links]
    csfh_connectors += [(n, "output") for n in OUTPUT_NAMES.values()]
    csfh_connectors.append(("contact.count", "output"))
    act_params = _bindable(actuator_md, actuator_start_values(s, voltage_in_fmu=True), where)
    act_connectors = [("theta", "input")] if s.moment else []
    act_connectors += [(n, "output") for n in ACTUATOR_COLUMNS]
    root = ET.Element(
        _q("ssd:SystemStructureDescription"),
        {
            "version": "1.0",
            "name": scene.name,
            "description": scene.description or scene.name,
            "generationTool": f"csfh {__version__}",
        },
    )
    system = ET.SubElement(
        root,
        _q("ssd:System"),
        {
            "name": scene.name,
            "description": "csfh (hinge) driven by combdrive (comb-drive actuator, voltage "
            "ramp in its ramp.* parameters): fixed-step co-simulation, inputs held over a step",
        },
    )
    elements = ET.SubElement(system, _q("ssd:Elements"))
    _component(elements, "csfh", csfh_md, csfh_connectors, csfh_params)
    _bind_inputs(elements[0], bound_inputs, csfh_md, hinge)
    _component(elements, "combdrive", actuator_md, act_connectors, act_params)
    _connections(system, links, s.moment)
    _experiment(root, stop_time, s.step)
    ET.indent(root)
    return ET.tostring(root, encoding="unicode", xml_declaration=True) + "\n"


def _zip(members: dict[str, bytes]) -> bytes:
    """A deterministic zip (fixed dates): the same inputs give the same bytes."""
    buffer = io.BytesIO()
    with zipfile.ZipFile(buffer, "w") as zf:
        for name, data in members.items():
            info = zipfile.ZipInfo(name, date_time=(1980, 1, 1, 0, 0, 0))
            info.compress_type = (
                zipfile.ZIP_STORED if name.endswith(".fmu") else (zipfile.ZIP_DEFLATED)
            )
            info.external_attr = 0o644 << 16
            zf.writestr(info, data)
    return buffer.getvalue()


def ssp_bytes(
    scene: Scene | str | Path,
    *,
    step: float | None = None,
    stop_time: float | None = None,
) -> bytes:
    """The SSP archive of the scene's coupled system (bytes), with the FMUs of this build.
    `step` and `stop_time` override the scene's communication step and stop time."""
    from .run import cosim_settings

    if not isinstance(scene, Scene):
        scene = load_scene(scene)
    settings = cosim_settings(scene, step=step)
    t_end = scene.stop_time if stop_time is None else stop_time
    try:
        check_horizon(
            t_end,
            settings.step,
            stop_key="stop_time" if stop_time is None else "stop time",
            interval_key="cosim.step" if step is None else "step",
        )
    except SceneError as exc:
        raise SceneError(f"{scene.source or scene.name}: {exc}") from None
    csfh_fmu, act_fmu = fmu_path(), combdrive_fmu_path()
    ssd = ssd_text(scene, settings, t_end, description(str(csfh_fmu)), description(str(act_fmu)))
    return _zip(
        {
            SSD_NAME: ssd.encode("utf-8"),
            COMPONENTS["csfh"]: csfh_fmu.read_bytes(),
            COMPONENTS["combdrive"]: act_fmu.read_bytes(),
        }
    )


def write_ssp(
    scene: Scene | str | Path,
    path: str | Path,
    *,
    step: float | None = None,
    stop_time: float | None = None,
) -> Path:
    """Write the scene's SSP archive to `path`, whole or not at all (csfh.output)."""
    path = Path(path)
    if not path.parent.is_dir():
        raise ResultsError(f"{path}: the directory {path.parent} does not exist")
    check_target(path)  # a device, FIFO or directory is refused before the archive is built
    data = ssp_bytes(scene, step=step, stop_time=stop_time)
    return write_bytes(path, data)


def cache_dir() -> Path:
    """$CSFH_CACHE, else $XDG_CACHE_HOME/csfh, else ~/.cache/csfh."""
    if os.environ.get("CSFH_CACHE"):
        return Path(os.environ["CSFH_CACHE"])
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "csfh"


def ssp_path(scene: str | Path = "combdrive") -> Path:
    """The SSP archive of a scene's coupled system (default: the built-in ``combdrive``),
    made on first use from the FMUs this package uses (`csfh.fmu_path`,
    `csfh.combdrive_fmu_path`) and kept in the cache (`cache_dir`) under a name that holds the
    SHA-256 of both FMUs, the scene file and the csfh version: a rebuilt FMU gets a new archive,
    so the archive always holds the FMUs of the same build."""
    loaded = load_scene(scene)
    h = hashlib.sha256(f"csfh {__version__} ssp {FORMAT}\n".encode())
    for part in (fmu_path(), combdrive_fmu_path()):
        h.update(part.read_bytes())
    source = Path(loaded.source) if loaded.source else None
    if source is not None and source.is_file():
        h.update(source.read_bytes())
    else:  # a scene without a file: its repr stands for its content
        h.update(repr(loaded).encode())
    path = cache_dir() / "ssp" / f"{loaded.name}-{h.hexdigest()[:20]}.ssp"
    if not path.exists():
        path.parent.mkdir(parents=True, exist_ok=True)
        write_ssp(loaded, path)
    return path


# ------------------------------------------------------------------------------------------
# running an archive in the two importers


def read_bindings(path: str | Path) -> dict[str, dict[str, tuple[str, str]]]:
    """component -> {parameter name: (type, value text)} of the inline ParameterBindings."""
    with zipfile.ZipFile(path) as zf:
        root = ET.fromstring(zf.read(SSD_NAME))
    out: dict[str, dict[str, tuple[str, str]]] = {}
    for comp in root.iterfind("ssd:System/ssd:Elements/ssd:Component", NS):
        params: dict[str, tuple[str, str]] = {}
        for p in comp.iterfind(
            "ssd:ParameterBindings/ssd:ParameterBinding/ssd:ParameterValues/ssv:ParameterSet/"
            "ssv:Parameters/ssv:Parameter",
            NS,
        ):
            (typed,) = list(p)
            params[p.get("name", "")] = (typed.tag.split("}")[1], typed.get("value", ""))
        out[comp.get("name", "")] = params
    return out


def default_experiment(path: str | Path) -> tuple[float, float]:
    """(stop time, fixed step) of the archive's DefaultExperiment."""
    with zipfile.ZipFile(path) as zf:
        root = ET.fromstring(zf.read(SSD_NAME))
    experiment = root.find("ssd:DefaultExperiment", NS)
    fixed = root.find(
        "ssd:DefaultExperiment/ssd:Annotations/ssc:Annotation/osp:Algorithm/osp:FixedStepAlgorithm",
        NS,
    )
    if experiment is None or fixed is None:
        raise CosimError(f"{path}: no DefaultExperiment with a fixed step")
    return float(experiment.get("stopTime", "nan")), float(fixed.get("baseStepSize", "nan"))


def simulate_with_fmpy(path: str | Path, stop_time: float | None = None) -> np.ndarray:
    """Run the archive with fmpy's SSP master (fmpy.ssp.simulation.simulate_ssp), giving it the
    archive's parameter bindings (which it reads but does not apply by itself) and the stop
    time and step of its DefaultExperiment. Returns fmpy's structured array: a row per step,
    its `time` the start of the step and its values those after it."""
    from fmpy.ssp.simulation import simulate_ssp
    from fmpy.ssp.ssd import Parameter, ParameterSet

    t_end, step = default_experiment(path)
    pset = ParameterSet(name="bindings")
    for comp, params in read_bindings(path).items():
        for name, (kind, text) in params.items():
            # fmpy sets a Boolean as value != 0.0: give it a number, not the text "false"
            value: Any = float(text in ("true", "1")) if kind == "Boolean" else text
            pset.parameters.append(Parameter(name=f"{comp}.{name}", type=kind, value=value))
    return simulate_ssp(
        str(path),
        stop_time=t_end if stop_time is None else stop_time,
        step_size=step,
        parameter_set=pset,
    )


def simulate_with_libcosim(
    path: str | Path, variables: dict[str, list[str]], stop_time: float | None = None
) -> dict[str, np.ndarray]:
    """Run the archive with libcosim's SSP loader (libcosimpy CosimExecution.from_ssp_file: the
    step from the archive's annotation) and return "t" and "component.variable" at every
    communication point, for the Real or Integer `variables` (component -> names)."""
    from libcosimpy.CosimEnums import CosimVariableType
    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimLogging import CosimLogLevel, log_output_level
    from libcosimpy.CosimObserver import CosimObserver

    from .libcosim_master import _last_error, _libcosim_samples

    t_end, step = default_experiment(path)
    t_end = t_end if stop_time is None else stop_time
    step_ns = round(step * 1e9)
    n = max(1, round(t_end / step))
    log_output_level(CosimLogLevel.FATAL)
    try:
        ex = CosimExecution.from_ssp_file(str(Path(path).resolve()))
    except AssertionError:
        raise CosimError(f"libcosim cannot load {path}: {_last_error()}") from None
    series = CosimObserver.create_time_series(buffer_size=n + 1)
    ex.add_observer(series)
    watched: list[tuple[str, int, int, bool]] = []
    for comp, names in variables.items():
        index = ex.slave_index_from_instance_name(comp)
        info = {v.name.decode(): v for v in ex.slave_variables(index)}
        for name in names:
            var = info[name]
            integer = var.type == CosimVariableType.INTEGER.value
            kind = CosimVariableType.INTEGER if integer else CosimVariableType.REAL
            series.start_time_series(index, var.reference, kind)
            watched.append((f"{comp}.{name}", index, var.reference, integer))
    for k in range(n):
        if not ex.step():
            raise CosimError(f"libcosim: step {k} of {path} failed: {_last_error()}")
    if ex.status().current_time != n * step_ns:
        raise CosimError(f"libcosim stopped at {ex.status().current_time} ns")
    out = {"t": np.arange(n + 1) * (step_ns * 1e-9)}
    for key, index, ref, integer in watched:
        out[key] = _libcosim_samples(series, index, ref, n + 1, integer)
    return out
