"""csfh design: the study file's checks, the Pareto front, the Sobol wiring on the Ishigami
function, the scene files written, the reproduction of the best design by csfh shock, resuming
an interrupted study, and the same design.json on a Dask cluster of separate processes."""

from __future__ import annotations

import json
import math
import os
import signal
import socket
import subprocess
import sys
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from csfh.batch.store import ResultStore
from csfh.batch.tasks import scene_fingerprint
from csfh.cli.main import main
from csfh.model.scene import load_scene
from csfh.studies.design import evaluate, run, search, sensitivity
from csfh.studies.design.spec import StudyError, load_study, study_from_dict

STUDY = """
[variables]
"contact.R2 - contact.R1" = [10e-6, 30e-6]
"flexure.h" = [4e-6, 8e-6]

[shock]
condition = "JESD22-B104-E"
directions = [90.0, 270.0]

[constraints]
flexure_margin = 0.5

[objectives]
names = ["flexure_stress", "contacts", "parasitic"]
search = "flexure_stress"
parasitic_moment = 1e-9

[sampling]
samples = 8

[search]
generations = 1
population = 2
best = 2

[sensitivity]
samples = 0
"""


@pytest.fixture(scope="module")
def designed(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A small study of the mems scene, run serially."""
    d = tmp_path_factory.mktemp("design")
    (d / "study.toml").write_text(STUDY)
    args = ["design", "mems", str(d / "study.toml"), "--out", str(d / "out"), "--workers", "1"]
    assert main([*args, "--quiet"]) == 0
    return d / "out"


@pytest.fixture
def study_file(designed: Path) -> Path:
    """The study file of `designed` (its path is part of the report)."""
    return designed.parent / "study.toml"


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({"variables": {"flexure.hh": [1.0, 2.0]}}, "variables.'flexure.hh' is not a real"),
        ({"variables": {"flexure.h": [2e-6, 1e-6]}}, "variables.'flexure.h' = [2e-06, 1e-06]"),
        ({"variables": {"flexure.h": [1e-6]}}, "must be a range [low, high]"),
        ({"shock": {"condition": "X", "peak_g": 1.0}}, "either condition or peak_g"),
        ({"shock": {"law": "Moreau"}}, "shock.law = 'Moreau' is not an event-driven model"),
        ({"shock": {"directions": 0}}, "shock.directions = 0 must be an integer >= 1"),
        ({"objectives": {"names": ["x"]}}, "objectives.names: 'x' is not one of"),
        ({"objectives": {"search": "contacts", "names": ["parasitic"]}}, "objectives.search"),
        ({"constraints": {"flexure_margin": 1.5}}, "constraints.flexure_margin = 1.5"),
        ({"sampling": {"method": "grid"}}, "sampling.method = 'grid'"),
        ({"searching": {}}, "unknown key 'searching'"),
        ({"report": {"axes": ["flexure.h", "flexure.b"]}}, "'flexure.b' is not a design variable"),
        ({"sensitivity": {"samples": 48}}, "sensitivity.samples = 48 must be 0 or a power of 2"),
        ({"quick": {"generations": 0}}, "quick.generations = 0 must be an integer >= 1"),
        (
            {"variables": {"contact.R2 - contact.R1": [1e-5, 2e-5], "contact.R2": [1.0, 2.0]}},
            "give either 'contact.R2 - contact.R1' or 'contact.R2', not both",
        ),
    ],
)
def test_a_bad_study_is_one_line_naming_the_key(change: dict[str, Any], message: str) -> None:
    import tomllib

    data = tomllib.loads(STUDY)
    for table, values in change.items():
        data[table] = {**data.get(table, {}), **values} if table != "variables" else values
    with pytest.raises(StudyError) as exc:
        study_from_dict(data, "s.toml")
    text = str(exc.value)
    assert text.startswith("s.toml: ") and message in text and "\n" not in text


def test_the_cli_reports_a_bad_study_on_one_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    bad = tmp_path / "bad.toml"
    bad.write_text(STUDY.replace('"flexure.h" = [4e-6, 8e-6]', '"flexure.h" = [4e-6]'))
    assert main(["design", "mems", str(bad), "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "variables.'flexure.h'" in err
    assert main(["design", "central", "--out", str(tmp_path / "o")]) == 2
    assert "no built-in design study" in capsys.readouterr().err


def test_a_range_the_model_refuses_is_one_line_before_any_run(tmp_path: Path) -> None:
    bad = tmp_path / "bad.toml"
    bad.write_text(STUDY.replace("[10e-6, 30e-6]", "[10e-6, 300e-6]"))
    with pytest.raises(StudyError) as exc:
        run.design("mems", bad, out=tmp_path / "o", workers=1)
    text = str(exc.value)
    assert "variables.'contact.R2 - contact.R1' = 0.0003 is refused" in text, text
    assert "contact.R1" in text and not (tmp_path / "o" / "tasks.jsonl").exists()


def test_the_built_in_studies_load_with_their_quick_values() -> None:
    for name in ("mems", "csfh"):
        study = load_study(load_scene(name))
        quick = study.quick_study()
        assert quick.samples < study.samples and len(quick.directions) < len(study.directions)


def test_quick_replaces_only_what_its_table_names() -> None:
    import tomllib

    data = tomllib.loads(STUDY)
    assert study_from_dict(data).quick_study().directions == (90.0, 270.0)
    data["quick"] = {"directions": 3, "samples": 2}
    quick = study_from_dict(data).quick_study()
    assert quick.directions == (0.0, 120.0, 240.0) and quick.samples == 2
    assert quick.generations == 1 and quick.sensitivity_samples == 0


def test_the_sensitivity_runs_through_the_study(tmp_path: Path) -> None:
    text = STUDY.replace("directions = [90.0, 270.0]", "directions = [90.0]")
    text = text.replace("[sensitivity]\nsamples = 0", "[sensitivity]\nsamples = 2")
    (tmp_path / "s.toml").write_text(text)
    outcome = run.design("mems", tmp_path / "s.toml", out=tmp_path / "o", workers=1)
    sens = outcome.result["sensitivity"]
    assert sens["direction"] == 90.0
    assert sens["design"]["evaluations"] == 2 * (2 + 2)
    assert sens["paper"]["evaluations"] == 2 * (len(sens["paper"]["inputs"]) + 2)
    for part in ("design", "paper"):
        for name in ("flexure_stress", "contacts", "parasitic"):
            r = sens[part]["indices"][name]
            assert len(r["ST"]) == len(sens[part]["inputs"]), (part, name)
    data = json.loads((tmp_path / "o" / "design.json").read_text())
    assert set(data["sensitivity"]["paper"]["table4_spearman"]) == {
        "flexure_stress",
        "contacts",
        "parasitic",
    }
    assert (tmp_path / "o" / "design_sensitivity.png").is_file()


def test_pareto_keeps_the_non_dominated_rows() -> None:
    values = np.array([[1, 5], [2, 2], [3, 3], [5, 1], [2, 2], [1, 6]], dtype=float)
    assert search.pareto(values).tolist() == [0, 1, 3]


def test_sobol_wiring_gives_the_ishigami_indices() -> None:
    a, b = 7.0, 0.1

    def ishigami(x: np.ndarray) -> dict[str, np.ndarray]:
        y = np.sin(x[:, 0]) + a * np.sin(x[:, 1]) ** 2 + b * x[:, 2] ** 4 * np.sin(x[:, 0])
        return {"y": y}

    v1 = 0.5 * (1 + b * math.pi**4 / 5) ** 2
    v2 = a**2 / 8
    v13 = 8 * b**2 * math.pi**8 / 225
    v = v1 + v2 + v13
    s1 = [v1 / v, v2 / v, 0.0]
    st = [(v1 + v13) / v, v2 / v, v13 / v]
    ranges = [(-math.pi, math.pi)] * 3
    r = sensitivity.sobol_indices(["x1", "x2", "x3"], ranges, ishigami, 4096, 1)
    got = r["indices"]["y"]
    assert r["evaluations"] == 4096 * 5
    for i in range(3):
        assert abs(got["S1"][i] - s1[i]) < 0.03 and abs(got["ST"][i] - st[i]) < 0.03, i
        assert got["S1_conf"][i] < 0.1 and got["ST_conf"][i] < 0.1


def test_the_agreement_with_table4_is_a_rank_correlation() -> None:
    inputs = ["R1", "m1", "beta", "h"]  # mean Table 4 levels 2.4, 1, 2.6, 2
    st = {"same": [0.3, 0.0, 0.4, 0.2], "reversed": [0.1, 0.4, 0.0, 0.2]}
    zero = [0.0] * 4
    indices = {
        k: {"S1": zero, "S1_conf": zero, "ST": v, "ST_conf": zero, "constant": False}
        for k, v in st.items()
    }
    indices["flat"] = {"S1": zero, "S1_conf": zero, "ST": zero, "ST_conf": zero, "constant": True}
    rho = sensitivity.table4_agreement({"inputs": inputs, "indices": indices})
    assert rho["same"] == pytest.approx(1.0) and rho["reversed"] == pytest.approx(-1.0)
    assert rho["flat"] is None


def test_the_static_equilibrium_solves_a_nonlinear_spring() -> None:
    k = np.array([[3.0, 1.0, 0.0], [1.0, 2.0, 0.5], [0.0, 0.5, 1.0]])
    target = np.array([1e-5, -2e-5, 0.03])

    def forces(q: np.ndarray) -> np.ndarray:
        d = q - target
        return -(k @ d) - 50.0 * d**3

    q = evaluate.equilibrium(forces, np.zeros(3), np.array([1e-4, 1e-4, 1.0]))
    assert np.allclose(q, target, rtol=1e-10, atol=0)


def test_the_parasitic_motion_grows_with_the_load_and_falls_with_thickness() -> None:
    scene = load_scene("mems")
    small = evaluate.parasitic(scene, {}, 1e-9)
    large = evaluate.parasitic(scene, {}, 2e-9)
    thick = evaluate.parasitic(scene, {"flexure.h": 8e-6}, 1e-9)
    assert large["parasitic"] > 1.5 * small["parasitic"] > 0
    assert thick["parasitic"] < small["parasitic"] and thick["rotation"] < small["rotation"]


def test_the_best_designs_scene_files_and_shock_reproduce_them(
    designed: Path, tmp_path: Path
) -> None:
    data = json.loads((designed / "design.json").read_text())
    best = data["best"]
    assert len(best) == 2 and best[0]["feasible"]
    assert best[0]["flexure_stress"] <= best[1]["flexure_stress"]
    feasible = [d for d in data["designs"] if d["feasible"]]
    assert min(d["objectives"]["flexure_stress"] for d in feasible) == best[0]["flexure_stress"]
    e = best[0]
    scene = load_scene(designed / e["scene"])
    base = load_scene("mems").with_parameters(**e["parameters"])
    assert scene_fingerprint(scene) == scene_fingerprint(base)
    assert math.isclose(
        scene.parameters["contact.R1"],
        0.2e-3 - e["variables"]["contact.R2 - contact.R1"],
        rel_tol=1e-15,
    )
    out = tmp_path / "shock"
    args = ["shock", str(designed / e["scene"]), "--condition", e["condition"]]
    args += ["--direction", str(e["direction"]), "--models", e["law"], "--out", str(out)]
    main([*args, "--quiet", "--workers", "1"])
    shock = json.loads((out / "shock.json").read_text())
    row = shock["result"]["models"][e["law"]]["directions"][0]
    for key in ("flexure_stress", "contact_pressure", "flexure_margin", "contact_margin"):
        assert math.isclose(row[key], e[key], rel_tol=1e-9), key
    assert row["contacts"] == e["contacts"]
    text = (designed / "design.md").read_text()
    assert "design_region.png" in text and e["scene"] in text


def test_an_interrupted_study_keeps_its_designs_and_resumes(
    designed: Path, study_file: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    calls = [0]
    real = evaluate.execute

    def interrupted(*args: Any, **kwargs: Any) -> Any:
        calls[0] += 1
        if calls[0] == 4:  # in the search, after the samples
            raise KeyboardInterrupt
        return real(*args, **kwargs)

    monkeypatch.setattr(evaluate, "execute", interrupted)
    out = tmp_path / "out"
    with pytest.raises(KeyboardInterrupt):
        run.design("mems", study_file, out=out, workers=1)
    kept = len(ResultStore(out))
    assert kept == 2 * (1 + 1 + 8)  # the scene's design, the centre and the samples
    monkeypatch.setattr(evaluate, "execute", real)
    outcome = run.design("mems", study_file, out=out, workers=1)
    assert outcome.run_info["reused"] >= kept and outcome.run_info["computed"] > 0
    assert (out / "design.json").read_text() == (designed / "design.json").read_text()


DASK = Path(sys.executable).with_name("dask")


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


@contextmanager
def _dask(*args: str) -> Iterator[None]:
    """`dask ARGS` in the background, its process group ended (by its id) at the end."""
    proc = subprocess.Popen(
        [str(DASK), *args],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
        start_new_session=True,
    )
    try:
        yield
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
        proc.wait()


def test_a_dask_cluster_of_processes_gives_the_same_design(
    designed: Path, study_file: Path, tmp_path: Path
) -> None:
    distributed = pytest.importorskip("distributed")
    if not DASK.exists():
        pytest.skip("the dask command is not installed")
    port = str(_free_port())
    address = f"tcp://127.0.0.1:{port}"
    with _dask("scheduler", "--host", "127.0.0.1", "--port", port, "--no-dashboard"):
        worker = ["worker", address, "--nworkers", "2", "--nthreads", "1", "--no-dashboard"]
        with _dask(*worker):
            with distributed.Client(address, timeout="20s") as client:
                client.wait_for_workers(2, timeout=30)
            out = tmp_path / "dask"
            args = ["design", "mems", str(study_file), "--out", str(out), "--dask", address]
            assert main([*args, "--quiet"]) == 0
    assert (out / "design.json").read_text() == (designed / "design.json").read_text()
    for e in json.loads((out / "design.json").read_text())["best"]:
        assert (out / e["scene"]).read_text() == (designed / e["scene"]).read_text()
