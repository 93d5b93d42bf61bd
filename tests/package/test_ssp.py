"""The coupled system as an SSP 1.0 archive (csfh.cosim.ssp, `csfh cosim --export-ssp`,
`csfh.ssp_path`): its structure against the SSP schema and the FMUs' interfaces, and the two SSP
importers (libcosim's loader, fmpy's SSP master) running it like `csfh cosim`."""

from __future__ import annotations

import io
import math
import os
import tomllib
import zipfile
from pathlib import Path
from typing import Any
from xml.etree import ElementTree as ET

import numpy as np
import pytest
from csfh_command import run_csfh
from fmpy import read_model_description
from oracles import K_COMB

import csfh
from csfh.cosim.fmpy_master import run_fmpy
from csfh.cosim.run import cosim_settings, cosimulate
from csfh.cosim.ssp import (
    NS,
    SSD_NAME,
    read_bindings,
    simulate_with_fmpy,
    simulate_with_libcosim,
    write_ssp,
)
from csfh.model.scene import load_scene, scene_from_dict

ROOT = Path(__file__).resolve().parents[2]
SCENE_FILE = ROOT / "python" / "csfh" / "scenes" / "combdrive.toml"
T = 0.3  # s: the ramp and the first two contacts of the combdrive scene
WATCH = {
    "csfh": ["body1.x", "body1.y", "body1.theta", "body1.vy", "contact.count"],
    "combdrive": ["F", "F_x", "F_y", "M"],
}


@pytest.fixture(scope="module")
def archive(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The combdrive scene exported by the command line."""
    path = tmp_path_factory.mktemp("ssp") / "combdrive.ssp"
    proc = run_csfh("cosim", "combdrive", "--export-ssp", str(path))
    assert proc.returncode == 0, proc.stderr
    assert str(path) in proc.stdout
    return path


def ssd_root(path: Path) -> ET.Element:
    with zipfile.ZipFile(path) as zf:
        return ET.fromstring(zf.read(SSD_NAME))


def rewrite(path: Path, target: Path, change: Any) -> Path:
    """A copy of the archive whose SSD is changed by change(root)."""
    root = ssd_root(path)
    change(root)
    with zipfile.ZipFile(path) as src, zipfile.ZipFile(target, "w") as dst:
        for info in src.infolist():
            data = src.read(info)
            if info.filename == SSD_NAME:
                data = ET.tostring(root, encoding="utf-8", xml_declaration=True)
            dst.writestr(info, data)
    return target


# ------------------------------------------------------------------------------------------
# the archive


def test_archive_is_valid_ssp_and_matches_the_fmus(archive: Path) -> None:
    """The SSD validates against the SSP 1.0 schema (shipped with fmpy); every component's
    source is in the archive, byte for byte the FMU of this build; every connector is a variable
    of that FMU with the matching causality and type; connections go from an output to an
    input; every parameter binding names a parameter (or input) of the FMU with its type."""
    lxml = pytest.importorskip("lxml.etree")
    import fmpy.ssp.ssd

    schema_dir = Path(fmpy.ssp.ssd.__file__).parent / "schema"
    schema = lxml.XMLSchema(file=str(schema_dir / "SystemStructureDescription.xsd"))
    with zipfile.ZipFile(archive) as zf:
        names = set(zf.namelist())
        doc = lxml.fromstring(zf.read(SSD_NAME))
        assert schema.validate(doc), schema.error_log
        root = ET.fromstring(zf.read(SSD_NAME))
        assert root.get("version") == "1.0"
        comps = root.findall("ssd:System/ssd:Elements/ssd:Component", NS)
        assert [c.get("name") for c in comps] == ["csfh", "combdrive"]
        built = {"csfh": csfh.fmu_path(), "combdrive": csfh.combdrive_fmu_path()}
        kinds: dict[tuple[str, str], str] = {}
        for comp in comps:
            name, source = comp.get("name", ""), comp.get("source", "")
            assert source in names and source.startswith("resources/")
            data = zf.read(source)
            assert data == built[name].read_bytes()
            md = read_model_description(io.BytesIO(data))
            variables = {v.name: v for v in md.modelVariables}
            for c in comp.iterfind("ssd:Connectors/ssd:Connector", NS):
                var = variables[c.get("name", "")]
                assert var.causality == c.get("kind"), c.get("name")
                (typed,) = list(c)
                assert typed.tag == f"{{{NS['ssc']}}}{var.type}", c.get("name")
                kinds[(name, var.name)] = var.causality
            bound = read_bindings(archive)[name]
            assert bound
            for pname, (ptype, _) in bound.items():
                var = variables[pname]
                assert var.causality in ("parameter", "input") and var.type == ptype, pname
    links = {
        (c.get("startElement"), c.get("startConnector"), c.get("endElement"), c.get("endConnector"))
        for c in root.iterfind("ssd:System/ssd:Connections/ssd:Connection", NS)
    }
    assert links == {
        ("combdrive", "F_x", "csfh", "F_ext[1]"),
        ("combdrive", "F_y", "csfh", "F_ext[2]"),
        ("combdrive", "M", "csfh", "M_ext"),
        ("csfh", "body1.theta", "combdrive", "theta"),
    }
    for a, out, b, inp in links:
        assert kinds[(a, out)] == "output" and kinds[(b, inp)] == "input"


def test_bindings_and_experiment_are_the_scenes(archive: Path) -> None:
    """Every value of the scene file is bound, and nothing else: read here from the TOML."""
    scene = tomllib.loads(SCENE_FILE.read_text())
    cosim = scene["cosim"]
    expected_act = {k: v for k, v in cosim["actuator"].items()}
    expected_act.update({f"ramp.{k}": v for k, v in cosim["voltage"].items()})
    state = dict(zip(("x", "y", "theta"), scene["initial"]["q"], strict=True))
    state.update(zip(("vx", "vy", "omega"), scene["initial"]["u"], strict=True))
    expected_csfh: dict[str, Any] = {f"initial.body1.{k}": v for k, v in state.items()}
    expected_csfh["initial.from_parameters"] = True
    expected_csfh["flexure.enabled"] = scene["parts"]["flexure"]
    expected_csfh["friction.enabled"] = scene["parts"]["friction"]

    def parsed(kind: str, text: str) -> Any:
        return {"Real": float, "Integer": int, "Boolean": lambda s: s == "true"}[kind](text)

    bound = read_bindings(archive)
    got = {c: {n: parsed(*tv) for n, tv in params.items()} for c, params in bound.items()}
    assert got == {"csfh": expected_csfh, "combdrive": expected_act}
    root = ssd_root(archive)
    experiment = root.find("ssd:DefaultExperiment", NS)
    assert experiment is not None
    assert float(experiment.get("startTime", "nan")) == 0.0
    assert float(experiment.get("stopTime", "nan")) == scene["stop_time"]
    fixed = experiment.find(
        "ssd:Annotations/ssc:Annotation/osp:Algorithm/osp:FixedStepAlgorithm", NS
    )
    assert fixed is not None and float(fixed.get("baseStepSize", "nan")) == cosim["step"]


def test_export_is_atomic_and_bad_input_is_one_line(tmp_path: Path) -> None:
    target = tmp_path / "system.ssp"
    target.write_bytes(b"previous")
    bad = tmp_path / "bad.toml"
    text = SCENE_FILE.read_text().replace('engine = "fmpy"', "tolerance = 1e-9")
    bad.write_text(text)
    cases = [
        (["csfh", "--export-ssp", str(target)], "the scene has no [cosim] section"),
        ([str(bad), "--export-ssp", str(target)], "cosim.tolerance = 1e-09 cannot be carried"),
        (["combdrive", "--export-ssp", str(tmp_path / "no" / "x.ssp")], "does not exist"),
    ]
    for args, message in cases:
        proc = run_csfh("cosim", *args)
        assert proc.returncode == 2, proc.stderr
        lines = proc.stderr.strip().splitlines()
        assert len(lines) == 1 and message in lines[0], proc.stderr
    assert target.read_bytes() == b"previous"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bad.toml", "system.ssp"]


def test_ssp_path_is_made_from_the_fmus_of_this_build(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setenv("CSFH_CACHE", str(tmp_path / "cache"))
    path = csfh.ssp_path("combdrive")
    assert path.parent.parent == tmp_path / "cache"
    with zipfile.ZipFile(path) as zf:
        assert zf.read("resources/csfh.fmu") == csfh.fmu_path().read_bytes()
        assert zf.read("resources/combdrive.fmu") == csfh.combdrive_fmu_path().read_bytes()
    mtime = path.stat().st_mtime_ns
    assert csfh.ssp_path("combdrive") == path and path.stat().st_mtime_ns == mtime
    # another build of the hinge FMU: another archive, holding that build
    other = tmp_path / "other" / "csfh.fmu"
    other.parent.mkdir()
    other.write_bytes(csfh.fmu_path().read_bytes() + b"\0")
    (other.parent / "combdrive.fmu").write_bytes(csfh.combdrive_fmu_path().read_bytes())
    monkeypatch.setenv("CSFH_FMU", str(other))
    second = csfh.ssp_path("combdrive")
    assert second != path
    with zipfile.ZipFile(second) as zf:
        assert zf.read("resources/csfh.fmu") == other.read_bytes()


# ------------------------------------------------------------------------------------------
# the importers run it like `csfh cosim`


def test_libcosim_runs_the_archive_like_csfh_cosim(archive: Path, libcosim: None) -> None:
    """libcosim's SSP loader and `csfh cosim --engine libcosimpy` (with the voltage evaluated
    in the actuator, as the archive does) drive the same binaries with the same values through
    the same algorithm (Jacobi, exchange at initialization): the results are identical. The
    fmpy master loop agrees to round-off (1e-11 m, 1e-3 of the FMU's absolute tolerance)."""
    ssp = simulate_with_libcosim(archive, WATCH, stop_time=T)
    ours = cosimulate("combdrive", engine="libcosimpy", stop_time=T, voltage_in_fmu=True)
    fm = cosimulate("combdrive", engine="fmpy", stop_time=T, voltage_in_fmu=True)
    assert ssp["t"].shape == ours.t.shape == (3001,)
    for col, key in (("x", "body1.x"), ("y", "body1.y"), ("theta", "body1.theta")):
        np.testing.assert_array_equal(ssp[f"csfh.{key}"], ours[col], err_msg=col)
        np.testing.assert_allclose(ssp[f"csfh.{key}"], fm[col], rtol=0, atol=1e-11, err_msg=col)
    np.testing.assert_array_equal(ssp["combdrive.F"], ours["F_act"])
    assert ssp["csfh.contact.count"][-1] == len(ours.contacts) >= 2
    # the start state comes from initial.body1.* (the FMU's own start is x = y = 0.01 m)
    assert ssp["csfh.body1.x"][0] == ssp["csfh.body1.y"][0] == 0.0
    # the actuator evaluates the ramp of the scene at each communication point: F = k V(t)^2
    ramp = cosim_settings(load_scene("combdrive")).voltage
    V = np.array([ramp(t) for t in ssp["t"]])
    np.testing.assert_allclose(ssp["combdrive.F"], K_COMB * V**2, rtol=1e-13)
    np.testing.assert_allclose(
        ssp["combdrive.F_y"], K_COMB * V**2 * math.sin(math.pi / 2), rtol=1e-13
    )


def test_fmpy_runs_the_archive_like_our_master(archive: Path) -> None:
    """fmpy's SSP master (with the archive's bindings) against the fmpy master loop with fmpy's
    ordering: Jacobi with every connected input 0 over the first step. fmpy labels a row with
    the start of its step and records the values after it, so its row k is our row k+1; its
    time is a running sum of the step (round-off only)."""
    fm = simulate_with_fmpy(archive, stop_time=T)
    scene = load_scene("combdrive")
    ours = run_fmpy(
        scene, cosim_settings(scene), stop_time=T, voltage_in_fmu=True, initial_exchange=False
    )
    n = len(ours.t) - 1
    assert len(fm) >= n
    fm = fm[:n]
    np.testing.assert_allclose(fm["time"], ours.t[:-1], rtol=0, atol=1e-12)
    for col, key in (("x", "body1.x"), ("y", "body1.y"), ("theta", "body1.theta")):
        np.testing.assert_allclose(fm[f"csfh.{key}"], ours[col][1:], rtol=0, atol=1e-11)
    np.testing.assert_allclose(fm["csfh.body1.vy"], ours["vy"][1:], rtol=0, atol=1e-8)
    np.testing.assert_allclose(fm["combdrive.F"], ours["F_act"][1:], rtol=1e-12)
    assert fm["csfh.contact.count"][-1] == len(ours.contacts) >= 2
    # and fmpy's zero first step is a real difference from csfh cosim's initial exchange
    usual = run_fmpy(scene, cosim_settings(scene), stop_time=T, voltage_in_fmu=True)
    assert np.max(np.abs(usual["y"][1:] - fm["csfh.body1.y"])) > 1e-6


def test_a_variant_scene_round_trips(tmp_path: Path, libcosim: None) -> None:
    """No moment coupling, flexure off (a Boolean false, which fmpy's SSP master would set
    true from the text), the cylinder contact law (an Enumeration: bound as its Integer twin)."""
    data = tomllib.loads(SCENE_FILE.read_text())
    data["cosim"]["moment"] = False
    data["parts"]["flexure"] = False
    data["parameters"] = {"contact.law": "LN_cylinders"}
    scene = scene_from_dict(data, "variant.toml")
    path = write_ssp(scene, tmp_path / "variant.ssp", stop_time=T)
    bound = read_bindings(path)
    assert bound["csfh"]["contact.law_number"] == ("Integer", "3")
    assert bound["csfh"]["flexure.enabled"] == ("Boolean", "false")
    root = ssd_root(path)
    assert len(root.findall("ssd:System/ssd:Connections/ssd:Connection", NS)) == 2
    lc = simulate_with_libcosim(path, WATCH, stop_time=T)
    ours = cosimulate(scene, engine="libcosimpy", stop_time=T, voltage_in_fmu=True)
    np.testing.assert_array_equal(lc["csfh.body1.y"], ours["y"])
    fm = simulate_with_fmpy(path, stop_time=T)
    zero = run_fmpy(
        scene, cosim_settings(scene), stop_time=T, voltage_in_fmu=True, initial_exchange=False
    )
    n = len(zero.t) - 1
    # Until the ramp starts (t0 = 0.1 s, row 1000) the inputs are constant and both runs
    # identical to round-off. There fmpy's summed time (0.1 + 2e-15 s) gives the actuator a
    # force that differs in the last bit, so CVODE restarts in fmpy's run and not in ours (the
    # input did not change): two integration paths, each within the FMU's tolerance (absolute
    # 1e-8 m), that the impacts separate further. (With the moment coupled, theta changes the
    # inputs at every step and both restart every time: test_fmpy_runs_the_archive...)
    y_fmpy, y_ours = fm["csfh.body1.y"][:n], zero["y"][1:]
    np.testing.assert_allclose(y_fmpy[:999], y_ours[:999], rtol=0, atol=1e-11)
    np.testing.assert_allclose(y_fmpy, y_ours, rtol=0, atol=5e-7)
    combdrive = cosimulate("combdrive", engine="libcosimpy", stop_time=T, voltage_in_fmu=True)
    assert np.max(np.abs(lc["csfh.body1.y"] - combdrive["y"])) > 1e-6  # a different system


def test_a_dropped_connection_or_binding_changes_the_run(tmp_path: Path, libcosim: None) -> None:
    """Each connection and each binding that differs from the FMU's own start value matters:
    without it the importer runs another system (the intact archive reproduces itself exactly),
    or refuses it (ramp.t1 = 0 < ramp.t0). Connections in libcosim, bindings in fmpy (an FMU
    that refuses its parameters aborts the whole process in libcosim 0.0.6). The combdrive scene
    with the force at 1.2 rad instead of +Y, so that F_x carries a force (cos(pi/2) F is
    1e-14 N)."""
    data = tomllib.loads(SCENE_FILE.read_text())
    data["cosim"]["actuator"]["direction"] = 1.2
    archive = write_ssp(scene_from_dict(data, "tilted.toml"), tmp_path / "tilted.ssp")
    t_end = 0.15
    reference = simulate_with_libcosim(archive, WATCH, stop_time=t_end)

    def differs(path: Path) -> float:
        run = simulate_with_libcosim(path, WATCH, stop_time=t_end)
        return max(float(np.max(np.abs(run[k] - reference[k]))) for k in reference if k != "t")

    assert differs(archive) == 0.0
    root = ssd_root(archive)
    connections = root.findall("ssd:System/ssd:Connections/ssd:Connection", NS)
    for i, connection in enumerate(connections):

        def drop_connection(r: ET.Element, i: int = i) -> None:
            parent = r.find("ssd:System/ssd:Connections", NS)
            assert parent is not None
            parent.remove(parent.findall("ssd:Connection", NS)[i])

        path = rewrite(archive, tmp_path / f"c{i}.ssp", drop_connection)
        assert differs(path) > 1e-9, connection.attrib

    fmpy_reference = simulate_with_fmpy(archive, stop_time=t_end)
    columns = [n for n in fmpy_reference.dtype.names if n.startswith("csfh.body1")]

    def fmpy_differs(path: Path) -> float:
        try:
            run = simulate_with_fmpy(path, stop_time=t_end)
        except Exception:  # the FMU refused what is left: fmi2ExitInitializationMode
            return math.inf
        return max(float(np.max(np.abs(run[c] - fmpy_reference[c]))) for c in columns)

    with zipfile.ZipFile(archive) as zf:
        starts = {
            comp: {
                v.name: v.start
                for v in read_model_description(
                    io.BytesIO(zf.read(f"resources/{comp}.fmu"))
                ).modelVariables
            }
            for comp in ("csfh", "combdrive")
        }
    dropped = 0
    for comp, params in read_bindings(archive).items():
        for name, (kind, text) in params.items():
            if kind == "Real" and float(text) == float(starts[comp][name]):
                continue  # the FMU's own start value: dropping it changes nothing
            if kind != "Real" and text == str(starts[comp][name]).lower():
                continue

            def drop_binding(r: ET.Element, comp: str = comp, name: str = name) -> None:
                for c in r.iterfind("ssd:System/ssd:Elements/ssd:Component", NS):
                    if c.get("name") != comp:
                        continue
                    plist = c.find(
                        "ssd:ParameterBindings/ssd:ParameterBinding/ssd:ParameterValues/"
                        "ssv:ParameterSet/ssv:Parameters",
                        NS,
                    )
                    assert plist is not None
                    for p in plist.findall("ssv:Parameter", NS):
                        if p.get("name") == name:
                            plist.remove(p)

            path = rewrite(archive, tmp_path / f"{comp}-{name}.ssp", drop_binding)
            assert fmpy_differs(path) > 1e-9, (comp, name)
            dropped += 1
    # ramp.V0, V1, t0, t1, arm[1], direction and the start state (x = y = 0, not 0.01)
    assert dropped >= 9


def test_fmu_ramp_and_initial_parameters(tmp_path: Path) -> None:
    """The FMU features the archive relies on, alone: the actuator's ramp (a step when t0 = t1,
    t1 < t0 refused) and the hinge's start state from initial.body1.*."""
    from fmpy import simulate_fmu

    act = str(csfh.combdrive_fmu_path())
    r = simulate_fmu(
        act,
        stop_time=0.4,
        output_interval=0.1,
        start_values={"ramp.V0": 100.0, "ramp.V1": 300.0, "ramp.t0": 0.1, "ramp.t1": 0.3},
        output=["F"],
    )
    V = np.interp(r["time"], [0.0, 0.1, 0.3, 0.4], [100.0, 100.0, 300.0, 300.0])
    np.testing.assert_allclose(r["F"], K_COMB * V**2, rtol=1e-13)
    with pytest.raises(Exception, match="status 3"):
        simulate_fmu(act, stop_time=0.1, start_values={"ramp.t0": 0.2, "ramp.t1": 0.1})
    hinge = str(csfh.fmu_path())
    start = {"initial.body1.x": 1e-3, "initial.body1.y": -2e-3, "initial.body1.omega": 0.5}
    with_flag = simulate_fmu(
        hinge,
        stop_time=1e-3,
        output_interval=1e-3,
        start_values={**start, "initial.from_parameters": True},
        output=["body1.x", "body1.y", "body1.omega"],
    )
    assert (with_flag["body1.x"][0], with_flag["body1.y"][0]) == (1e-3, -2e-3)
    assert with_flag["body1.omega"][0] == 0.5
    without = simulate_fmu(
        hinge, stop_time=1e-3, output_interval=1e-3, start_values=start, output=["body1.x"]
    )
    assert without["body1.x"][0] == 0.01  # the flag off: the states' own start values
    assert not os.environ.get("CSFH_CACHE")  # the fixtures did not leak the cache setting
