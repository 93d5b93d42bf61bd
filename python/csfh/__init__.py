"""csfh: dynamics of a Conjugate-Surface Flexure Hinge with impacts and friction.

The model is an FMI 2.0 FMU (model exchange and co-simulation) built from the C core in
``fmu_src/``; this package ships it, with the same core as a shared library, and adds scenes,
the Moreau time stepper, comparisons and reports on top.

    >>> import csfh
    >>> scene = csfh.load_scene("csfh")
    >>> run = csfh.simulate(scene, "LN_cylinders")      # FMU, model exchange, CVode
    >>> rigid = csfh.moreau(scene, stick_rule="memory")  # Moreau midpoint stepper
"""

from __future__ import annotations

from .model.scene import Scene, SceneError, load_scene, scene_from_dict
from .paths import core_library_path, fmu_path
from .runners.moreau import moreau
from .runners.simulate import simulate
from .studies.compare import compare
from .trajectory import Trajectory

__all__ = [
    "Scene",
    "SceneError",
    "Trajectory",
    "compare",
    "core_library_path",
    "fmu_path",
    "load_scene",
    "moreau",
    "scene_from_dict",
    "simulate",
]
__version__ = "0.1.0"
