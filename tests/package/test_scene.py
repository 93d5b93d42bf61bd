"""Scenes (csfh.model.scene): the built-in ones, the examples of the documentation, the presets,
and a bad scene file or a start deep in the bore refused in one line that names the file, the key
and the value, by the loader and by the command line."""

from __future__ import annotations

from pathlib import Path

import pytest
from csfh_command import run_csfh

from csfh.model.instance import core_model
from csfh.model.scene import SceneError, load_scene, scene_from_dict


def test_builtin_scenes() -> None:
    central, asym, full = (load_scene(n) for n in ("central", "asymmetric", "csfh"))
    assert central.q0 == (0.0, 0.01, 0.0) and not central.flexure and not central.friction
    assert asym.q0 == (0.01, 0.01, 0.0) and not asym.flexure and asym.friction
    assert full.q0 == (0.01, 0.01, 0.0) and full.flexure and full.friction


def test_the_scene_example_in_the_documentation_is_a_valid_scene() -> None:
    """The example scene in csfh.model.scene's docstring parses and loads as documented."""
    import textwrap
    import tomllib

    import csfh.model.scene as scene_module

    doc = str(scene_module.__doc__)
    example = textwrap.dedent(doc[doc.index("    name = ") :])
    data = tomllib.loads(example)
    scene = scene_from_dict(data, "docstring")
    assert scene.models == ("LN_spheres", "LN_cylinders", "LN_ESDU", "Moreau")
    assert scene.integrator.stick_rule == "paper" and scene.parameters == {"contact.cr": 0.9}
    assert scene.q0 == (0.01, 0.01, 0.0) and scene.inputs == {"F_ext[1]": 0.0}


def test_the_scene_example_of_the_user_guide_is_a_valid_scene() -> None:
    import tomllib

    text = (Path(__file__).resolve().parents[2] / "docs/guide/harness.md").read_text()
    example = text.split("```toml\n", 1)[1].split("```", 1)[0]
    scene = scene_from_dict(tomllib.loads(example), "guide")
    assert scene.name == "my_drop" and scene.models == (
        "LN_spheres",
        "LN_cylinders",
        "LN_ESDU",
        "Moreau",
    )


def test_consistent_preset_values() -> None:
    scene = scene_from_dict({"name": "c", "preset": "consistent"})
    model = core_model(scene)
    assert model.get("contact.E1") == 100e9
    assert model.get("contact.n_cylinders") == 1.0
    assert model.get("contact.K_spheres") == pytest.approx(9.8289e10, rel=1e-4)  # 4.1
    assert scene.stick_rule == "memory"


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ('name = "x"\nstop_time = -1', "stop_time = -1 must be > 0"),
        ('name = "x"\nbogus = 1', "unknown key 'bogus'"),
        ('name = "x"\n[parameters]\n"contact.nope" = 1', "unknown parameter 'contact.nope'"),
        ('name = "x"\n[parameters]\n"contact.cr" = 1.5', "contact.cr = 1.5 is out of range"),
        ('name = "x"\n[parameters]\n"contact.R1" = 0.3', "contact.R1 = 0.3"),
        ('name = "x"\n[parameters]\n"contact.law" = "Bogus"', 'contact.law = "Bogus"'),
        ('name = "x"\n[initial]\nq = [0, 1]', "initial.q must be a list of 3 numbers"),
        ('name = "x"\npreset = "weird"', "preset = 'weird'"),
        ('name = "x"\n[integrator]\nstick_rule = "loose"', "stick_rule = 'loose'"),
        ("name = ", "not valid TOML"),
    ],
)
def test_bad_scene_file_one_line_error(tmp_path: Path, text: str, message: str) -> None:
    path = tmp_path / "bad.toml"
    path.write_text(text)
    with pytest.raises(SceneError, match=r"bad\.toml") as info:
        load_scene(path)
    assert message in str(info.value)
    proc = run_csfh("run", str(path), "--law", "Moreau", "--out", str(tmp_path / "o"))
    assert proc.returncode == 2
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and message in lines[0], proc.stderr


def test_scene_loader_refuses_a_deep_start(tmp_path) -> None:
    """The scene loader says the same in one line, and the CLI exits 2 with it."""

    from csfh.model.scene import SceneError, scene_from_dict

    with pytest.raises(SceneError) as info:
        scene_from_dict({"name": "deep", "initial": {"q": [0.05, 0.0, 0.0]}})
    assert "\n" not in str(info.value)
    assert "0.03 m deep" in str(info.value) and "contact.max_initial_indentation" in str(info.value)
    path = tmp_path / "huge.toml"
    path.write_text('name = "huge"\n[initial]\nq = [1e10, 0.0, 0.0]\n')
    r = run_csfh("run", str(path), "--law", "LN_spheres", timeout=120)
    assert r.returncode == 2 and len(r.stderr.strip().splitlines()) == 1, r.stderr
    assert "deep in the bore" in r.stderr
    # an override of the limit lets a deeper start through (1.5e-3 m > 1e-3 m), up to the
    # harness's own limit of 1 % of R1 (1.8e-3 m: Hertz contact needs indentations small
    # against the radii), which no override raises
    scene_from_dict(
        {
            "name": "deep",
            "initial": {"q": [0.0215, 0.0, 0.0]},
            "parameters": {"contact.max_initial_indentation": 0.04},
        }
    )
    with pytest.raises(SceneError, match=r"at most 0\.01 contact\.R1 = 0\.0018 m"):
        scene_from_dict(
            {
                "name": "deep",
                "initial": {"q": [0.05, 0.0, 0.0]},
                "parameters": {"contact.max_initial_indentation": 0.04},
            }
        )
