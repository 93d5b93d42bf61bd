#!/usr/bin/env python3
"""Generate modelDescription.xml and the C variable table from variables.toml.

variables.toml is the single source of truth of the FMU interface: value references, names,
types, start values, ranges, units and the C storage of every variable. This script writes

    <outdir>/modelDescription.xml
    <outdir>/csfh_variables.h    (value references, enumerations, GUID)
    <outdir>/csfh_variables.c    (the table the FMI glue and the core library use)
    <outdir>/csfh_enums.h        (the enumerations as C enums)

With --fmi-version 3 the model description is FMI 3.0's (the same variables, value references,
start values, ranges and instantiation token; the C files are the same): the FMI 3.0 build of
the FMU (fmu_src/fmi/fmi3_glue.c) packages it. The FMI 3.0 co-simulation capabilities are the
[cosimulation] table's (translated) plus [fmi3_cosimulation]; the model-exchange event
indicators are the variables named by [model] event_indicator_variables (FMI 3.0 declares each
event indicator as a variable).

The same script serves every model of the repository (combdrive.toml: the comb-drive actuator).
Optional keys of [model] name the C side; their defaults are the csfh model's:

    c_prefix = "csfh"                 file names <prefix>_variables.h ..., macros <PREFIX>_...,
                                      the table <prefix>_variables[]
    c_struct = "csfh_model_t"         the C struct the table's offsets refer to
    c_include = "csfh_model.h"        the header that declares it
    log_events_description = "..."    description of the logEvents log category

The model's `version` is the package's (python/csfh/_version.py, the one place of the version;
CMake passes it as --version).

Usage: generate.py [--version X.Y.Z] [--fmi-version 2|3] VARIABLES_TOML OUTDIR
                   [--source-files NAME ...]
"""

from __future__ import annotations

import argparse
import hashlib
import math
import os
import re
import sys
import time
import tomllib
import uuid
from pathlib import Path
from xml.sax.saxutils import quoteattr

CAUSALITY_C = {
    "parameter": "CSFH_CAUS_PARAMETER",
    "calculatedParameter": "CSFH_CAUS_CALCULATED_PARAMETER",
    "input": "CSFH_CAUS_INPUT",
    "output": "CSFH_CAUS_OUTPUT",
    "local": "CSFH_CAUS_LOCAL",
    "independent": "CSFH_CAUS_INDEPENDENT",
}
TYPE_C = {
    "Real": "CSFH_TYPE_REAL",
    "Integer": "CSFH_TYPE_INTEGER",
    "Boolean": "CSFH_TYPE_BOOLEAN",
    "Enumeration": "CSFH_TYPE_ENUMERATION",
}
STATES_DEFAULT = "states"
LOG_EVENTS_DEFAULT = "Contact onsets and releases, mode changes"


def c_names(spec: dict) -> tuple[str, str, str, str]:
    """(prefix, PREFIX, struct, include) of the model's C side ([model] c_* keys, csfh default)."""
    model = spec["model"]
    prefix = model.get("c_prefix", "csfh")
    return (
        prefix,
        prefix.upper(),
        model.get("c_struct", "csfh_model_t"),
        model.get("c_include", "csfh_model.h"),
    )


# [default_experiment] of a spec without one
DEFAULT_EXPERIMENT = {"startTime": 0.0, "stopTime": 1.0, "tolerance": 1e-6}


class SpecError(Exception):
    pass


def c_ident(name: str) -> str:
    """body1.x -> BODY1_X, der(body1.x) -> DER_BODY1_X, F_ext[1] -> F_EXT_1."""
    s = re.sub(r"[^0-9A-Za-z]+", "_", name).strip("_")
    return s.upper()


def parse_range(text: str) -> tuple[float, float, bool, bool]:
    m = re.fullmatch(r"\s*([\[(])\s*([^,]+?)\s*,\s*([^,]+?)\s*([\])])\s*", text)
    if not m:
        raise SpecError(f"bad range {text!r}")
    lo = float(m.group(2)) if m.group(2) not in ("-inf",) else -math.inf
    hi = float(m.group(3)) if m.group(3) not in ("inf",) else math.inf
    return lo, hi, m.group(1) == "(", m.group(4) == ")"


def fmt_real(x: float) -> str:
    if math.isinf(x):
        return "INFINITY" if x > 0 else "-INFINITY"
    return repr(float(x))


def fmt_xml_real(x: float) -> str:
    return repr(float(x))


def load(path: Path) -> dict:
    with path.open("rb") as f:
        spec = tomllib.load(f)
    variables = spec["variables"]
    seen_vr: dict[tuple[str, int], str] = {}
    seen_name: set[str] = set()
    enums = {e["name"]: e for e in spec.get("enumerations", [])}
    units = {u["name"]: u for u in spec.get("units", [])}
    for v in variables:
        name = v["name"]
        if name in seen_name:
            raise SpecError(f"duplicate variable name {name}")
        seen_name.add(name)
        # FMI 2.0 value references are unique per base type; we keep them unique overall
        key = ("all", v["vr"])
        if key in seen_vr:
            raise SpecError(f"value reference {v['vr']} of {name} already used by {seen_vr[key]}")
        seen_vr[key] = name
        if v["type"] == "Enumeration" and v.get("declaredType") not in enums:
            raise SpecError(f"{name}: unknown declaredType {v.get('declaredType')}")
        if "unit" in v and v["unit"] not in units:
            raise SpecError(f"{name}: unit {v['unit']} not declared")
        if "range" in v:
            parse_range(v["range"])
    for e in enums.values():
        values = [it["value"] for it in e["items"]]
        if values != list(range(1, len(values) + 1)):
            raise SpecError(f"enumeration {e['name']} must be numbered 1..N in order")
    by_name = {v["name"]: v for v in variables}
    for v in variables:
        if "derivative_of" in v and not by_name.get(v["derivative_of"], {}).get("state"):
            raise SpecError(f"{v['name']}: derivative_of must name a state")
        for d in v.get("depends", []):
            if d not in by_name:
                raise SpecError(f"{v['name']}: depends on unknown variable {d}")
    return spec


def build_epoch(given: int | None) -> int:
    """The generation time: given, else $SOURCE_DATE_EPOCH (reproducible builds), else now."""
    if given is not None:
        return given
    env = os.environ.get("SOURCE_DATE_EPOCH", "")
    if env:
        try:
            return int(env)
        except ValueError:
            raise SpecError(f"SOURCE_DATE_EPOCH = {env!r} is not an integer") from None
    return int(time.time())


def guid_of(spec: dict) -> str:
    digest = hashlib.sha256(repr(spec).encode()).hexdigest()
    return "{" + str(uuid.UUID(digest[:32])) + "}"


# --------------------------------------------------------------------------------------------
# modelDescription.xml


def type_attributes(v: dict, units: dict, derivative: str | None) -> list[str]:
    """The attributes of a variable's type, the same in FMI 2.0 (on its type element) and FMI 3.0
    (on the variable): declaredType, quantity, unit, displayUnit, min, max, nominal, derivative
    (the reference the caller gives: FMI 2.0's index, FMI 3.0's value reference), start."""
    ta: list[str] = []
    if v["type"] == "Enumeration":
        ta.append(f'declaredType="{v["declaredType"]}"')
    quantity = v.get("quantity", units.get(v.get("unit", ""), {}).get("quantity"))
    if quantity and v["type"] == "Real":
        ta.append(f"quantity={quoteattr(quantity)}")
    for key in ("unit", "displayUnit"):
        if key in v:
            ta.append(f"{key}={quoteattr(v[key])}")
    if "range" in v:
        lo, hi, lo_open, hi_open = parse_range(v["range"])
        if v["type"] == "Integer":
            # open ends: the next integer inside
            bounds = (lo + 1 if lo_open else lo, hi - 1 if hi_open else hi)
            fmt_bound = lambda x: str(int(x))  # noqa: E731
        else:
            # FMI's min and max are inclusive: an open end is the next double inside, the
            # extreme value the FMU's check accepts
            bounds = (
                math.nextafter(lo, math.inf) if lo_open and math.isfinite(lo) else lo,
                math.nextafter(hi, -math.inf) if hi_open and math.isfinite(hi) else hi,
            )
            fmt_bound = fmt_xml_real
        if math.isfinite(bounds[0]):
            ta.append(f'min="{fmt_bound(bounds[0])}"')
        if math.isfinite(bounds[1]):
            ta.append(f'max="{fmt_bound(bounds[1])}"')
    if "nominal" in v:
        ta.append(f'nominal="{fmt_xml_real(v["nominal"])}"')
    if derivative is not None:
        ta.append(f'derivative="{derivative}"')
    if "start" in v:
        s = v["start"]
        if v["type"] == "Boolean":
            ta.append(f'start="{"true" if s else "false"}"')
        elif v["type"] == "Real":
            ta.append(f'start="{fmt_xml_real(s)}"')
        else:
            ta.append(f'start="{int(s)}"')
    return ta


def xml_model_description(
    spec: dict, guid: str, epoch: int, source_files: tuple[str, ...] = ()
) -> str:
    """The model description; `source_files` (file names under sources/) become <SourceFiles>
    of both interfaces (a source FMU, built by cmake/fmu.cmake)."""
    model = spec["model"]
    variables = spec["variables"]
    units = {u["name"]: u for u in spec.get("units", [])}
    generated = time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime(epoch))
    index = {v["name"]: i + 1 for i, v in enumerate(variables)}
    states = [v["name"] for v in variables if v.get("state")]
    inputs = [v["name"] for v in variables if v["causality"] == "input"]
    parameters = [v["name"] for v in variables if v["causality"] == "parameter"]
    out: list[str] = []
    w = out.append
    w('<?xml version="1.0" encoding="UTF-8"?>')
    w(
        f'<fmiModelDescription fmiVersion="2.0" modelName={quoteattr(model["modelName"])} '
        f'guid="{guid}" description={quoteattr(model["description"])} '
        f"author={quoteattr(model['author'])} version={quoteattr(model['version'])} "
        f'generationTool="csfh modelDescription/generate.py" '
        f'generationDateAndTime="{generated}" '
        f'variableNamingConvention="structured" '
        f'numberOfEventIndicators="{model["numberOfEventIndicators"]}">'
    )
    mi = model["modelIdentifier"]

    def interface(tag: str, attrs: str) -> None:
        """<ModelExchange>, <CoSimulation>: with <SourceFiles> when the FMU carries sources."""
        if not source_files:
            w(f"  <{tag} {attrs}/>")
            return
        w(f"  <{tag} {attrs}>")
        w("    <SourceFiles>")
        for name in source_files:
            w(f"      <File name={quoteattr(name)}/>")
        w("    </SourceFiles>")
        w(f"  </{tag}>")

    interface(
        "ModelExchange",
        f'modelIdentifier="{mi}" canGetAndSetFMUstate="true" '
        f'canSerializeFMUstate="true" canNotUseMemoryManagementFunctions="true" '
        f'completedIntegratorStepNotNeeded="true"',
    )
    if "cosimulation" in spec:
        cs = spec["cosimulation"]
        attrs = " ".join(f'{k}="{str(v).lower()}"' for k, v in cs.items())
        interface("CoSimulation", f'modelIdentifier="{mi}" {attrs}')
    w("  <UnitDefinitions>")
    for u in spec["units"]:
        base = {k: u[k] for k in ("kg", "m", "s", "A", "K", "mol", "cd", "rad") if k in u}
        displays = u.get("display", [])
        if not base and not displays:
            w(f"    <Unit name={quoteattr(u['name'])}/>")
            continue
        w(f"    <Unit name={quoteattr(u['name'])}>")
        if base or u["name"] == "1":
            w("      <BaseUnit " + " ".join(f'{k}="{val}"' for k, val in base.items()) + "/>")
        for d in displays:
            w(f'      <DisplayUnit name={quoteattr(d["name"])} factor="{d["factor"]!r}"/>')
        w("    </Unit>")
    w("  </UnitDefinitions>")
    if spec.get("enumerations"):  # the schema wants at least one SimpleType inside
        w("  <TypeDefinitions>")
    for e in spec.get("enumerations", []):
        w(f"    <SimpleType name={quoteattr(e['name'])} description={quoteattr(e['description'])}>")
        w("      <Enumeration>")
        for it in e["items"]:
            w(
                f'        <Item name={quoteattr(it["name"])} value="{it["value"]}" '
                f"description={quoteattr(it['description'])}/>"
            )
        w("      </Enumeration>")
        w("    </SimpleType>")
    if spec.get("enumerations"):
        w("  </TypeDefinitions>")
    w("  <LogCategories>")
    events = model.get("log_events_description", LOG_EVENTS_DEFAULT)
    w(f'    <Category name="logEvents" description={quoteattr(events)}/>')
    w('    <Category name="logStatusWarning" description="Calls that return fmi2Warning"/>')
    w(
        '    <Category name="logStatusError" '
        'description="Calls that return fmi2Error: bad input, illegal call sequences"/>'
    )
    w('    <Category name="logAll" description="Every FMI call"/>')
    w("  </LogCategories>")
    experiment = spec.get("default_experiment", DEFAULT_EXPERIMENT)
    w(
        "  <DefaultExperiment "
        + " ".join(
            f'{key}="{fmt_xml_real(experiment[key])}"'
            for key in ("startTime", "stopTime", "tolerance", "stepSize")
            if key in experiment
        )
        + "/>"
    )
    w("  <ModelVariables>")
    for i, v in enumerate(variables, start=1):
        attrs = [f"name={quoteattr(v['name'])}", f'valueReference="{v["vr"]}"']
        if "description" in v:
            attrs.append(f"description={quoteattr(v['description'])}")
        attrs.append(f'causality="{v["causality"]}"')
        attrs.append(f'variability="{v["variability"]}"')
        if "initial" in v:
            attrs.append(f'initial="{v["initial"]}"')
        w(f"    <!-- index {i} -->")
        w("    <ScalarVariable " + " ".join(attrs) + ">")
        derivative = str(index[v["derivative_of"]]) if "derivative_of" in v else None
        ta = type_attributes(v, units, derivative)
        w(f"      <{v['type']} " + " ".join(ta) + "/>")
        w("    </ScalarVariable>")
    w("  </ModelVariables>")

    def deps_of(v: dict) -> list[str]:
        d = v.get("depends", STATES_DEFAULT)
        return states if d == STATES_DEFAULT else list(d)

    def dep_attr(names: list[str]) -> str:
        return " ".join(str(index[n]) for n in sorted(set(names), key=lambda n: index[n]))

    def section(tag: str, unknowns: list[str]) -> None:
        """<Outputs>, <Derivatives>: omitted when empty (the schema wants an Unknown inside)."""
        if unknowns:
            w(f"    <{tag}>")
            out.extend(unknowns)
            w(f"    </{tag}>")

    w("  <ModelStructure>")
    section(
        "Outputs",
        [
            f'      <Unknown index="{index[v["name"]]}" dependencies="{dep_attr(deps_of(v))}"/>'
            for v in variables
            if v["causality"] == "output"
        ],
    )
    section(
        "Derivatives",
        [
            f'      <Unknown index="{index[v["name"]]}" dependencies="{dep_attr(deps_of(v))}"/>'
            for v in variables
            if "derivative_of" in v
        ],
    )
    w("    <InitialUnknowns>")
    initial_unknowns = []
    for v in variables:
        calculated_output = (
            v["causality"] == "output"
            and v.get("initial") in (None, "calculated")
            and "start" not in v
        )
        if calculated_output or v["causality"] == "calculatedParameter" or "derivative_of" in v:
            initial_unknowns.append(v)
    for v in sorted(initial_unknowns, key=lambda v: index[v["name"]]):
        if v["causality"] == "calculatedParameter":
            names = parameters
        elif (
            "derivative_of" in v
            and v.get("depends")
            and all(n in states for n in v["depends"])
            and len(v["depends"]) == 1
        ):
            names = deps_of(v)  # der(q) = u: no parameter enters
        else:
            names = (
                [n for n in deps_of(v) if n not in inputs]
                + parameters
                + [n for n in deps_of(v) if n in inputs]
            )
        w(f'      <Unknown index="{index[v["name"]]}" dependencies="{dep_attr(names)}"/>')
    w("    </InitialUnknowns>")
    w("  </ModelStructure>")
    w("</fmiModelDescription>")
    return "\n".join(out) + "\n"


# --------------------------------------------------------------------------------------------
# modelDescription.xml, FMI 3.0

FMI3_TYPE = {
    "Real": "Float64",
    "Integer": "Int32",
    "Boolean": "Boolean",
    "Enumeration": "Enumeration",
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
    "providesDirectionalDerivative": "providesDirectionalDerivatives",
}
# what the FMI 3.0 front-end adds to co-simulation (fmu_src/fmi/fmi3_glue.c): Event Mode, and
# fmi3DoStep returning early at an event when the importer allows it
FMI3_CS_DEFAULT = {
    "hasEventMode": True,
    "mightReturnEarlyFromDoStep": True,
    "canReturnEarlyAfterIntermediateUpdate": False,
    "providesIntermediateUpdate": False,
}


def fmi3_attr(value: object) -> str:
    return str(value).lower() if isinstance(value, bool) else str(value)


def xml_model_description_fmi3(
    spec: dict, guid: str, epoch: int, source_files: tuple[str, ...] = ()
) -> str:
    """The FMI 3.0 model description of the same interface: value references as in FMI 2.0
    (unique over all types), Real -> Float64, Integer -> Int32; ModelStructure by value
    reference; the instantiation token is the FMI 2.0 GUID."""
    model = spec["model"]
    variables = spec["variables"]
    units = {u["name"]: u for u in spec.get("units", [])}
    by_name = {v["name"]: v for v in variables}
    generated = time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime(epoch))
    states = [v["name"] for v in variables if v.get("state")]
    inputs = [v["name"] for v in variables if v["causality"] == "input"]
    parameters = [v["name"] for v in variables if v["causality"] == "parameter"]
    indicators = list(model.get("event_indicator_variables", []))
    if len(indicators) != model["numberOfEventIndicators"]:
        raise SpecError(
            f"[model] event_indicator_variables names {len(indicators)} variables, "
            f"numberOfEventIndicators is {model['numberOfEventIndicators']}"
        )
    for name in indicators:
        if name not in by_name or by_name[name]["type"] != "Real":
            raise SpecError(f"event indicator {name!r} is not a Real variable")
    out: list[str] = []
    w = out.append
    w('<?xml version="1.0" encoding="UTF-8"?>')
    w(
        f'<fmiModelDescription fmiVersion="3.0" modelName={quoteattr(model["modelName"])} '
        f'instantiationToken="{guid}" description={quoteattr(model["description"])} '
        f"author={quoteattr(model['author'])} version={quoteattr(model['version'])} "
        f'generationTool="csfh modelDescription/generate.py" '
        f'generationDateAndTime="{generated}" '
        f'variableNamingConvention="structured">'
    )
    mi = model["modelIdentifier"]

    def interface(tag: str, attrs: str) -> None:
        if not source_files:
            w(f"  <{tag} {attrs}/>")
            return
        # FMI 3.0 describes sources in sources/buildDescription.xml; the file list stays there
        w(f"  <{tag} {attrs}/>")

    interface(
        "ModelExchange",
        f'modelIdentifier="{mi}" canGetAndSetFMUState="true" canSerializeFMUState="true" '
        f'needsCompletedIntegratorStep="false"',
    )
    if "cosimulation" in spec:
        cs: dict[str, object] = {}
        for key, value in spec["cosimulation"].items():
            if key not in FMI3_CS_ATTRIBUTES:
                raise SpecError(f"[cosimulation] {key}: no FMI 3.0 equivalent known")
            if FMI3_CS_ATTRIBUTES[key] is not None:
                cs[FMI3_CS_ATTRIBUTES[key]] = value
        cs.update(FMI3_CS_DEFAULT)
        cs.update(spec.get("fmi3_cosimulation", {}))
        attrs = " ".join(f'{k}="{fmi3_attr(v)}"' for k, v in cs.items())
        interface("CoSimulation", f'modelIdentifier="{mi}" {attrs}')
    w("  <UnitDefinitions>")
    for u in spec["units"]:
        base = {k: u[k] for k in ("kg", "m", "s", "A", "K", "mol", "cd", "rad") if k in u}
        displays = u.get("display", [])
        if not base and not displays:
            w(f"    <Unit name={quoteattr(u['name'])}/>")
            continue
        w(f"    <Unit name={quoteattr(u['name'])}>")
        if base or u["name"] == "1":
            w("      <BaseUnit " + " ".join(f'{k}="{val}"' for k, val in base.items()) + "/>")
        for d in displays:
            w(f'      <DisplayUnit name={quoteattr(d["name"])} factor="{d["factor"]!r}"/>')
        w("    </Unit>")
    w("  </UnitDefinitions>")
    if spec.get("enumerations"):
        w("  <TypeDefinitions>")
        for e in spec["enumerations"]:
            w(
                f"    <EnumerationType name={quoteattr(e['name'])} "
                f"description={quoteattr(e['description'])}>"
            )
            for it in e["items"]:
                w(
                    f'      <Item name={quoteattr(it["name"])} value="{it["value"]}" '
                    f"description={quoteattr(it['description'])}/>"
                )
            w("    </EnumerationType>")
        w("  </TypeDefinitions>")
    w("  <LogCategories>")
    events = model.get("log_events_description", LOG_EVENTS_DEFAULT)
    w(f'    <Category name="logEvents" description={quoteattr(events)}/>')
    w('    <Category name="logStatusWarning" description="Calls that return fmi3Warning"/>')
    w(
        '    <Category name="logStatusError" '
        'description="Calls that return fmi3Error: bad input, illegal call sequences"/>'
    )
    w('    <Category name="logAll" description="Every FMI call"/>')
    w("  </LogCategories>")
    experiment = spec.get("default_experiment", DEFAULT_EXPERIMENT)
    w(
        "  <DefaultExperiment "
        + " ".join(
            f'{key}="{fmt_xml_real(experiment[key])}"'
            for key in ("startTime", "stopTime", "tolerance", "stepSize")
            if key in experiment
        )
        + "/>"
    )
    w("  <ModelVariables>")
    for v in variables:
        attrs = [f"name={quoteattr(v['name'])}", f'valueReference="{v["vr"]}"']
        if "description" in v:
            attrs.append(f"description={quoteattr(v['description'])}")
        attrs.append(f'causality="{v["causality"]}"')
        attrs.append(f'variability="{v["variability"]}"')
        if "initial" in v:
            attrs.append(f'initial="{v["initial"]}"')
        derivative = by_name[v["derivative_of"]]["vr"] if "derivative_of" in v else None
        attrs += type_attributes(v, units, None if derivative is None else str(derivative))
        w(f"    <{FMI3_TYPE[v['type']]} " + " ".join(attrs) + "/>")
    w("  </ModelVariables>")

    def deps_of(v: dict) -> list[str]:
        d = v.get("depends", STATES_DEFAULT)
        return states if d == STATES_DEFAULT else list(d)

    def dep_attr(names: list[str]) -> str:
        vrs = sorted({by_name[n]["vr"] for n in names})
        return " ".join(str(r) for r in vrs)

    def unknown(tag: str, v: dict, names: list[str] | None) -> None:
        deps = "" if names is None else f' dependencies="{dep_attr(names)}"'
        w(f'    <{tag} valueReference="{v["vr"]}"{deps}/>')

    w("  <ModelStructure>")
    for v in variables:
        if v["causality"] == "output":
            unknown("Output", v, deps_of(v))
    for v in variables:
        if "derivative_of" in v:
            unknown("ContinuousStateDerivative", v, deps_of(v))
    for v in variables:
        calculated_output = (
            v["causality"] == "output"
            and v.get("initial") in (None, "calculated")
            and "start" not in v
        )
        if not (
            calculated_output or v["causality"] == "calculatedParameter" or "derivative_of" in v
        ):
            continue
        if v["causality"] == "calculatedParameter":
            names = parameters
        elif (
            "derivative_of" in v
            and v.get("depends")
            and all(n in states for n in v["depends"])
            and len(v["depends"]) == 1
        ):
            names = deps_of(v)
        else:
            names = (
                [n for n in deps_of(v) if n not in inputs]
                + parameters
                + [n for n in deps_of(v) if n in inputs]
            )
        unknown("InitialUnknown", v, names)
    for name in indicators:
        unknown("EventIndicator", by_name[name], deps_of(by_name[name]))
    w("  </ModelStructure>")
    w("</fmiModelDescription>")
    return "\n".join(out) + "\n"


# --------------------------------------------------------------------------------------------
# C


def c_header(spec: dict, guid: str, source: str = "variables.toml") -> str:
    prefix, P, _, _ = c_names(spec)
    out: list[str] = []
    w = out.append
    w(f"/* Generated by modelDescription/generate.py from {source}. Do not edit. */")
    w(f"#ifndef {P}_VARIABLES_H")
    w(f"#define {P}_VARIABLES_H")
    w("")
    w('#include "csfh_vartable.h"')
    w('#include "csfh_visibility.h"')
    w("")
    w("CSFH_INTERNAL_BEGIN")
    w("")
    w(f'#define {P}_GUID "{guid}"')
    w(f'#define {P}_MODEL_IDENTIFIER "{spec["model"]["modelIdentifier"]}"')
    w(f"#define {P}_NUMBER_OF_STATES {sum(1 for v in spec['variables'] if v.get('state'))}")
    w(f"#define {P}_NUMBER_OF_EVENT_INDICATORS {spec['model']['numberOfEventIndicators']}")
    w(f"#define {P}_NUMBER_OF_VARIABLES {len(spec['variables'])}")
    w("")
    w("/* value references */")
    for v in spec["variables"]:
        w(f"#define {P}_VR_{c_ident(v['name'])} {v['vr']}u")
    w("")
    w(f"extern const csfh_variable_t {prefix}_variables[{P}_NUMBER_OF_VARIABLES];")
    w("")
    w("CSFH_INTERNAL_END")
    w("")
    w("#endif")
    return "\n".join(out) + "\n"


def c_enums(spec: dict, source: str = "variables.toml") -> str:
    prefix, P, _, _ = c_names(spec)
    out: list[str] = []
    w = out.append
    w(f"/* Generated by modelDescription/generate.py from {source}. Do not edit. */")
    w(f"#ifndef {P}_ENUMS_H")
    w(f"#define {P}_ENUMS_H")
    for e in spec.get("enumerations", []):
        w("")
        w(f"/* {e['description']} */")
        w("typedef enum {")
        for it in e["items"]:
            item = f"{P}_{c_ident(e['name'])}_{c_ident(it['name'])}"
            w(f"    {item} = {it['value']}, /* {it['description']} */")
        w(f"}} {prefix}_{re.sub(r'(?<!^)(?=[A-Z])', '_', e['name']).lower()}_t;")
        w(f"#define {P}_{c_ident(e['name'])}_COUNT {len(e['items'])}")
    w("")
    w("#endif")
    return "\n".join(out) + "\n"


def c_source(spec: dict, source: str = "variables.toml") -> str:
    prefix, P, struct, include = c_names(spec)
    enums = {e["name"]: e for e in spec.get("enumerations", [])}
    out: list[str] = []
    w = out.append
    w(f"/* Generated by modelDescription/generate.py from {source}. Do not edit. */")
    w("#include <math.h>")
    w("#include <stddef.h>")
    w(f'#include "{include}"')
    w(f'#include "{prefix}_variables.h"')
    w("")
    w(f"const csfh_variable_t {prefix}_variables[{P}_NUMBER_OF_VARIABLES] = {{")
    for v in spec["variables"]:
        field = v["field"]
        lo, hi, lo_open, hi_open, has_range = -math.inf, math.inf, 0, 0, 0
        if "range" in v:
            lo, hi, lo_open, hi_open = parse_range(v["range"])
            has_range = 1
        if v["type"] == "Enumeration":
            lo, hi, lo_open, hi_open, has_range = 1, len(enums[v["declaredType"]]["items"]), 0, 0, 1
        if v["type"] == "Boolean":
            lo, hi, has_range = 0, 1, 1
        start = v.get("start", 0)
        if isinstance(start, bool):
            start = int(start)
        storage = (
            "CSFH_STORE_COMPUTED" if field.startswith(("out.", "der[")) else "CSFH_STORE_PLAIN"
        )
        w(
            "    {"
            f'{v["vr"]}u, "{v["name"]}", {TYPE_C[v["type"]]}, {CAUSALITY_C[v["causality"]]}, '
            f"{int(v['variability'] == 'tunable')}, {int(bool(v.get('state')))}, {storage}, "
            f"offsetof({struct}, {field}), {1 if 'start' in v else 0}, {fmt_real(start)}, "
            f"{has_range}, {fmt_real(lo)}, {fmt_real(hi)}, {int(lo_open)}, {int(hi_open)}, "
            f"{fmt_real(v.get('nominal', 1.0))}"
            "},"
        )
    w("};")
    return "\n".join(out) + "\n"


VERSION_FILE = Path(__file__).resolve().parents[1] / "python" / "csfh" / "_version.py"


def package_version(path: Path = VERSION_FILE) -> str:
    """The version in python/csfh/_version.py (`__version__ = "X.Y.Z"`)."""
    m = re.search(r'^__version__ = "(\d+\.\d+\.\d+)"$', path.read_text(encoding="utf-8"), re.M)
    if m is None:
        raise SpecError(f'{path}: no line __version__ = "X.Y.Z"')
    return m.group(1)


def main(argv: list[str]) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--version", help="model version (default: python/csfh/_version.py)")
    ap.add_argument("variables", type=Path)
    ap.add_argument("outdir", type=Path)
    ap.add_argument(
        "--epoch",
        type=int,
        default=None,
        help="generationDateAndTime in seconds since 1970 (default: $SOURCE_DATE_EPOCH, else now)",
    )
    ap.add_argument(
        "--fmi-version",
        type=int,
        choices=(2, 3),
        default=2,
        help="the FMI version of modelDescription.xml (the C files are the same)",
    )
    ap.add_argument(
        "--source-files",
        nargs="+",
        default=[],
        metavar="NAME",
        help="the .c files under the FMU's sources/ (written as <SourceFiles>)",
    )
    args = ap.parse_args(argv)
    try:
        spec = load(args.variables)
        if "version" in spec["model"]:
            raise SpecError("[model] version: the version comes from python/csfh/_version.py")
        spec["model"]["version"] = args.version or package_version()
        epoch = build_epoch(args.epoch)
    except (SpecError, KeyError, OSError, tomllib.TOMLDecodeError) as exc:
        print(f"generate.py: {args.variables}: {exc}", file=sys.stderr)
        return 1
    guid = guid_of(spec)
    args.outdir.mkdir(parents=True, exist_ok=True)
    prefix = c_names(spec)[0]
    source = args.variables.name
    writer = xml_model_description_fmi3 if args.fmi_version == 3 else xml_model_description
    try:
        description = writer(spec, guid, epoch, tuple(args.source_files))
    except SpecError as exc:
        print(f"generate.py: {args.variables}: {exc}", file=sys.stderr)
        return 1
    files = {
        "modelDescription.xml": description,
        f"{prefix}_variables.h": c_header(spec, guid, source),
        f"{prefix}_enums.h": c_enums(spec, source),
        f"{prefix}_variables.c": c_source(spec, source),
    }
    for name, text in files.items():
        path = args.outdir / name
        if not path.exists() or path.read_text() != text:
            path.write_text(text)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
