"""modelDescription.xml of FMI 2.0 and FMI 3.0 from a variables file, one writer for both.

The document is built with ElementTree. What the two versions share (the root's attributes, the
interfaces, units, log categories, default experiment, the values of each variable's type
attributes, which unknowns the model structure lists and what they depend on) is written once;
what differs is in one table per version (FLAVOURS): element and attribute names, how a
variable and an enumeration are laid out, how an unknown and a dependency are referenced
(FMI 2.0: the variable's index, FMI 3.0: its value reference)."""

from __future__ import annotations

import math
import time
import xml.etree.ElementTree as ET
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from spec import Spec, SpecError, dependencies, parse_range, quantity_of, states

Variable = dict[str, Any]
Ref = Callable[[str], int]
"""How the model structure refers to a variable, by name (FMI 2.0: index, FMI 3.0: vr)."""
Deps = Callable[["Unknown"], dict[str, str]]
"""The dependencies (and dependenciesKind, where the variable gives its kinds) attributes of an
unknown."""
LOG_EVENTS_DEFAULT = "Contact onsets and releases, mode changes"
BASE_UNITS = ("kg", "m", "s", "A", "K", "mol", "cd", "rad")
EXPERIMENT_KEYS = ("startTime", "stopTime", "tolerance", "stepSize")
DECLARATION = '<?xml version="1.0" encoding="UTF-8"?>\n'


def real(x: float) -> str:
    return repr(float(x))


def boolean(x: object) -> str:
    return str(x).lower()


# --------------------------------------------------------------------------------------------
# what the versions share


def type_attributes(v: Variable, spec: Spec, derivative: str | None) -> dict[str, str]:
    """The attributes of a variable's type, the same in FMI 2.0 (on its type element) and FMI 3.0
    (on the variable): declaredType, quantity, unit, displayUnit, min, max, nominal, derivative
    (the reference the caller gives: FMI 2.0's index, FMI 3.0's value reference), start."""
    ta: dict[str, str] = {}
    if v["type"] == "Enumeration":
        ta["declaredType"] = v["declaredType"]
    quantity = quantity_of(spec, v)
    if quantity:
        ta["quantity"] = quantity
    for key in ("unit", "displayUnit"):
        if key in v:
            ta[key] = v[key]
    if "range" in v:
        ta.update(bounds(v))
    if "nominal" in v:
        ta["nominal"] = real(v["nominal"])
    if derivative is not None:
        ta["derivative"] = derivative
    if "start" in v:
        ta["start"] = start_text(v)
    return ta


def start_text(v: Variable) -> str:
    if v["type"] == "Boolean":
        return boolean(bool(v["start"]))
    if v["type"] == "Real":
        return real(v["start"])
    return str(int(v["start"]))


def bounds(v: Variable) -> dict[str, str]:
    """min and max of a range: FMI's are inclusive, so an open end is the next value inside (an
    Integer's next integer, a Real's next double: the extreme value the FMU's check accepts)."""
    lo, hi, lo_open, hi_open = parse_range(v["range"])
    if v["type"] == "Integer":
        ends = (lo + 1 if lo_open else lo, hi - 1 if hi_open else hi)
        text: Callable[[float], str] = lambda x: str(int(x))  # noqa: E731
    else:
        ends = (
            math.nextafter(lo, math.inf) if lo_open and math.isfinite(lo) else lo,
            math.nextafter(hi, -math.inf) if hi_open and math.isfinite(hi) else hi,
        )
        text = real
    out = {}
    for key, end in zip(("min", "max"), ends, strict=True):
        if math.isfinite(end):
            out[key] = text(end)
    return out


@dataclass(frozen=True)
class Unknown:
    """An entry of ModelStructure: `kind` is output, derivative, initial or indicator."""

    kind: str
    variable: Variable
    depends: list[str]
    kinds: dict[str, str] | None = None  # depends_kind: name -> kind, the rest "dependent"


def _initial_dependencies(spec: Spec, v: Variable) -> list[str]:
    """What an initial unknown depends on: a calculated parameter on the parameters; der(q) = u
    on its one state alone; anything else on its dependencies and the parameters."""
    variables = spec["variables"]
    parameters = [w["name"] for w in variables if w["causality"] == "parameter"]
    if v["causality"] == "calculatedParameter":
        return parameters
    deps = dependencies(spec, v)
    if "derivative_of" in v and len(v.get("depends", [])) == 1 and deps[0] in states(spec):
        return deps
    return deps + parameters


def _is_initial_unknown(v: Variable) -> bool:
    calculated_output = (
        v["causality"] == "output" and v.get("initial") in (None, "calculated") and "start" not in v
    )
    return calculated_output or v["causality"] == "calculatedParameter" or "derivative_of" in v


def unknowns(spec: Spec) -> list[Unknown]:
    """ModelStructure in the order both versions write it: outputs, derivatives, initial
    unknowns, event indicators (only FMI 3.0 lists those), each in the order of the variables."""
    variables = spec["variables"]
    by_name = {v["name"]: v for v in variables}
    out = [
        Unknown("output", v, dependencies(spec, v), v.get("depends_kind"))
        for v in variables
        if v["causality"] == "output"
    ]
    out += [
        Unknown("derivative", v, dependencies(spec, v), v.get("depends_kind"))
        for v in variables
        if "derivative_of" in v
    ]
    out += [
        Unknown("initial", v, _initial_dependencies(spec, v))
        for v in variables
        if _is_initial_unknown(v)
    ]
    for name in spec["model"].get("event_indicator_variables", []):
        v = by_name[name]
        out.append(Unknown("indicator", v, dependencies(spec, v)))
    return out


# --------------------------------------------------------------------------------------------
# what differs: one Flavour per FMI version


@dataclass(frozen=True)
class Flavour:
    version: str
    token: str  # the root's attribute of the GUID
    prefix: str  # of the status names in the log categories
    model_exchange: dict[str, str]
    derivatives: Callable[[Spec], dict[str, str]]  # the capability flags of both interfaces
    root_extra: Callable[[Spec], dict[str, str]]
    cosimulation: Callable[[Spec], dict[str, str]]
    source_files: bool  # FMI 2.0 lists them in the interfaces; FMI 3.0 in buildDescription.xml
    enumeration: Callable[[ET.Element, dict[str, Any]], None]
    variable: Callable[[ET.Element, int, Variable, str | None, Spec], None]
    reference: Callable[[Spec], dict[str, int]]  # variable name -> how FMI refers to it
    structure: Callable[[ET.Element, list[Unknown], Deps, Ref], None]


def _enumeration2(parent: ET.Element, e: dict[str, Any]) -> None:
    simple = ET.SubElement(parent, "SimpleType", name=e["name"], description=e["description"])
    _items(ET.SubElement(simple, "Enumeration"), e)


def _enumeration3(parent: ET.Element, e: dict[str, Any]) -> None:
    _items(
        ET.SubElement(parent, "EnumerationType", name=e["name"], description=e["description"]), e
    )


def _items(parent: ET.Element, e: dict[str, Any]) -> None:
    for it in e["items"]:
        ET.SubElement(
            parent, "Item", name=it["name"], value=str(it["value"]), description=it["description"]
        )


def _variable_attributes(v: Variable) -> dict[str, str]:
    attrs = {"name": v["name"], "valueReference": str(v["vr"])}
    if "description" in v:
        attrs["description"] = v["description"]
    attrs["causality"] = v["causality"]
    attrs["variability"] = v["variability"]
    if "initial" in v:
        attrs["initial"] = v["initial"]
    return attrs


def _variable2(
    parent: ET.Element, index: int, v: Variable, derivative: str | None, spec: Spec
) -> None:
    parent.append(ET.Comment(f" index {index} "))
    scalar = ET.SubElement(parent, "ScalarVariable", _variable_attributes(v))
    ET.SubElement(scalar, v["type"], type_attributes(v, spec, derivative))


FMI3_TYPE = {
    "Real": "Float64",
    "Integer": "Int32",
    "Boolean": "Boolean",
    "Enumeration": "Enumeration",
}


def _variable3(
    parent: ET.Element, index: int, v: Variable, derivative: str | None, spec: Spec
) -> None:
    attrs = _variable_attributes(v) | type_attributes(v, spec, derivative)
    ET.SubElement(parent, FMI3_TYPE[v["type"]], attrs)


def _structure2(parent: ET.Element, entries: list[Unknown], deps: Deps, ref: Ref) -> None:
    """<Outputs>, <Derivatives> (omitted when empty: the schema wants an Unknown inside) and
    <InitialUnknowns> of <Unknown index=...>; event indicators are only counted in FMI 2.0."""
    for kind, tag in (
        ("output", "Outputs"),
        ("derivative", "Derivatives"),
        ("initial", "InitialUnknowns"),
    ):
        selected = [u for u in entries if u.kind == kind]
        if not selected and kind != "initial":
            continue
        section = ET.SubElement(parent, tag)
        for u in selected:
            ET.SubElement(section, "Unknown", {"index": str(ref(u.variable["name"]))} | deps(u))


FMI3_UNKNOWN = {
    "output": "Output",
    "derivative": "ContinuousStateDerivative",
    "initial": "InitialUnknown",
    "indicator": "EventIndicator",
}


def _structure3(parent: ET.Element, entries: list[Unknown], deps: Deps, ref: Ref) -> None:
    for u in entries:
        ET.SubElement(
            parent, FMI3_UNKNOWN[u.kind], {"valueReference": str(ref(u.variable["name"]))} | deps(u)
        )


def _cosimulation2(spec: Spec) -> dict[str, str]:
    return {k: boolean(v) for k, v in spec["cosimulation"].items()} | _derivatives2(spec)


def _derivative_flags(spec: Spec) -> tuple[bool, bool]:
    """[partial_derivatives]: (directional, adjoint), both interfaces; False when absent."""
    d = spec.get("partial_derivatives", {})
    return bool(d.get("providesDirectionalDerivative", False)), bool(
        d.get("providesAdjointDerivatives", False)
    )


def _derivatives2(spec: Spec) -> dict[str, str]:
    """FMI 2.0 has the directional derivative only."""
    return {"providesDirectionalDerivative": boolean(_derivative_flags(spec)[0])}


def _derivatives3(spec: Spec) -> dict[str, str]:
    directional, adjoint = _derivative_flags(spec)
    return {
        "providesDirectionalDerivatives": boolean(directional),
        "providesAdjointDerivatives": boolean(adjoint),
    }


# [cosimulation] keys of FMI 2.0 and their FMI 3.0 names (None: not in FMI 3.0)
FMI3_CS_ATTRIBUTES = {
    "canHandleVariableCommunicationStepSize": "canHandleVariableCommunicationStepSize",
    "canInterpolateInputs": None,  # FMI 3.0: recommendedIntermediateInputSmoothness
    "maxOutputDerivativeOrder": "maxOutputDerivativeOrder",
    "canRunAsynchronuously": None,
    "canBeInstantiatedOnlyOncePerProcess": "canBeInstantiatedOnlyOncePerProcess",
    "canNotUseMemoryManagementFunctions": None,
    "canGetAndSetFMUstate": "canGetAndSetFMUState",
    "canSerializeFMUstate": "canSerializeFMUState",
}
# what the FMI 3.0 front-end adds to co-simulation (fmu_src/fmu/fmi3/fmi3_glue.c): Event Mode, and
# fmi3DoStep returning early at an event when the importer allows it
FMI3_CS_DEFAULT = {
    "hasEventMode": True,
    "mightReturnEarlyFromDoStep": True,
    "canReturnEarlyAfterIntermediateUpdate": False,
    "providesIntermediateUpdate": False,
}


def _cosimulation3(spec: Spec) -> dict[str, str]:
    cs: dict[str, object] = {}
    for key, value in spec["cosimulation"].items():
        if key not in FMI3_CS_ATTRIBUTES:
            raise SpecError(f"[cosimulation] {key}: no FMI 3.0 equivalent known")
        name = FMI3_CS_ATTRIBUTES[key]
        if name is not None:
            cs[name] = value
    cs.update(FMI3_CS_DEFAULT)
    cs.update(spec.get("fmi3_cosimulation", {}))
    text = {k: boolean(v) if isinstance(v, bool) else str(v) for k, v in cs.items()}
    return text | _derivatives3(spec)


def _index(spec: Spec) -> dict[str, int]:
    return {v["name"]: i + 1 for i, v in enumerate(spec["variables"])}


def _value_reference(spec: Spec) -> dict[str, int]:
    return {v["name"]: v["vr"] for v in spec["variables"]}


FLAVOURS = {
    2: Flavour(
        version="2.0",
        token="guid",
        prefix="fmi2",
        model_exchange={
            "canGetAndSetFMUstate": "true",
            "canSerializeFMUstate": "true",
            "canNotUseMemoryManagementFunctions": "true",
            "completedIntegratorStepNotNeeded": "true",
        },
        derivatives=_derivatives2,
        root_extra=lambda spec: {
            "numberOfEventIndicators": str(spec["model"]["numberOfEventIndicators"])
        },
        cosimulation=_cosimulation2,
        source_files=True,
        enumeration=_enumeration2,
        variable=_variable2,
        reference=_index,
        structure=_structure2,
    ),
    3: Flavour(
        version="3.0",
        token="instantiationToken",
        prefix="fmi3",
        model_exchange={
            "canGetAndSetFMUState": "true",
            "canSerializeFMUState": "true",
            "needsCompletedIntegratorStep": "false",
        },
        derivatives=_derivatives3,
        root_extra=lambda spec: {},
        cosimulation=_cosimulation3,
        source_files=False,
        enumeration=_enumeration3,
        variable=_variable3,
        reference=_value_reference,
        structure=_structure3,
    ),
}


# --------------------------------------------------------------------------------------------
# the document


def _root(spec: Spec, f: Flavour, guid: str, epoch: int) -> ET.Element:
    model = spec["model"]
    return ET.Element(
        "fmiModelDescription",
        {
            "fmiVersion": f.version,
            "modelName": model["modelName"],
            f.token: guid,
            "description": model["description"],
            "author": model["author"],
            "version": model["version"],
            "generationTool": "csfh modelDescription/generate.py",
            "generationDateAndTime": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime(epoch)),
            "variableNamingConvention": "structured",
        }
        | f.root_extra(spec),
    )


def _interfaces(root: ET.Element, spec: Spec, f: Flavour, source_files: tuple[str, ...]) -> None:
    """<ModelExchange>, <CoSimulation>, with <SourceFiles> for a source FMU (FMI 2.0)."""
    mi = {"modelIdentifier": spec["model"]["modelIdentifier"]}
    interfaces = [("ModelExchange", mi | f.model_exchange | f.derivatives(spec))]
    if "cosimulation" in spec:
        interfaces.append(("CoSimulation", mi | f.cosimulation(spec)))
    for tag, attrs in interfaces:
        element = ET.SubElement(root, tag, attrs)
        if source_files and f.source_files:
            files = ET.SubElement(element, "SourceFiles")
            for name in source_files:
                ET.SubElement(files, "File", name=name)


def _units(root: ET.Element, spec: Spec) -> None:
    definitions = ET.SubElement(root, "UnitDefinitions")
    for u in spec["units"]:
        unit = ET.SubElement(definitions, "Unit", name=u["name"])
        base = {k: str(u[k]) for k in BASE_UNITS if k in u}
        displays = u.get("display", [])
        if base or (displays and u["name"] == "1"):  # "1": every exponent 0
            ET.SubElement(unit, "BaseUnit", base)
        for d in displays:
            ET.SubElement(unit, "DisplayUnit", name=d["name"], factor=repr(d["factor"]))


def _log_categories(root: ET.Element, spec: Spec, f: Flavour) -> None:
    categories = ET.SubElement(root, "LogCategories")
    for name, description in (
        ("logEvents", spec["model"].get("log_events_description", LOG_EVENTS_DEFAULT)),
        ("logStatusWarning", f"Calls that return {f.prefix}Warning"),
        ("logStatusError", f"Calls that return {f.prefix}Error: bad input, illegal call sequences"),
        ("logAll", "Every FMI call"),
    ):
        ET.SubElement(categories, "Category", name=name, description=description)


def _variables(root: ET.Element, spec: Spec, f: Flavour, ref: dict[str, int]) -> None:
    element = ET.SubElement(root, "ModelVariables")
    for i, v in enumerate(spec["variables"], start=1):
        derivative = str(ref[v["derivative_of"]]) if "derivative_of" in v else None
        f.variable(element, i, v, derivative, spec)


def model_description(
    spec: Spec, guid: str, epoch: int, fmi_version: int = 2, source_files: tuple[str, ...] = ()
) -> str:
    """The model description of FMI `fmi_version` (2 or 3); `source_files` (file names under
    sources/) become <SourceFiles> of both FMI 2.0 interfaces (a source FMU, cmake/fmu.cmake).
    FMI 3.0: the same variables, value references, start values and ranges, Real -> Float64,
    Integer -> Int32; the instantiation token is the FMI 2.0 GUID."""
    f = FLAVOURS[fmi_version]
    ref = f.reference(spec)
    root = _root(spec, f, guid, epoch)
    _interfaces(root, spec, f, source_files)
    _units(root, spec)
    if spec.get("enumerations"):  # the schema wants at least one type inside
        types = ET.SubElement(root, "TypeDefinitions")
        for e in spec["enumerations"]:
            f.enumeration(types, e)
    _log_categories(root, spec, f)
    experiment = spec["default_experiment"]
    ET.SubElement(
        root,
        "DefaultExperiment",
        {k: real(experiment[k]) for k in EXPERIMENT_KEYS if k in experiment},
    )
    _variables(root, spec, f, ref)

    def deps(u: Unknown) -> dict[str, str]:
        by_ref = {ref[n]: n for n in u.depends}
        order = sorted(by_ref)
        out = {"dependencies": " ".join(str(r) for r in order)}
        if u.kinds is not None:
            out["dependenciesKind"] = " ".join(u.kinds.get(by_ref[r], "dependent") for r in order)
        return out

    f.structure(ET.SubElement(root, "ModelStructure"), unknowns(spec), deps, ref.__getitem__)
    return serialize(root)


def serialize(root: ET.Element) -> str:
    """The document as text: two spaces per level, attributes in the order they were given,
    empty elements as <tag .../> (ElementTree writes "<tag ... />": the space is dropped; no
    attribute value can hold "/>", ElementTree escapes ">")."""
    ET.indent(root, space="  ")
    return DECLARATION + ET.tostring(root, encoding="unicode").replace(" />", "/>") + "\n"
