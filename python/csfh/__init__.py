"""csfh: dynamics of a Conjugate-Surface Flexure Hinge with impacts and friction.

The model is an FMI 2.0 FMU (model exchange and co-simulation) built from the C core in
``fmu_src/``; this package ships it, with the same core as a shared library, and adds scenes,
the Moreau time stepper, comparisons and reports on top.

    >>> import csfh
    >>> scene = csfh.load_scene("csfh")
    >>> run = csfh.simulate(scene, "LN_cylinders")      # FMU, model exchange, CVode
    >>> rigid = csfh.moreau(scene, stick_rule="memory")  # Moreau midpoint stepper
    >>> driven = csfh.cosimulate(csfh.load_scene("combdrive"))  # with the comb-drive FMU

The model itself is documented in ``docs/model.md``.
"""

from __future__ import annotations

from ._paths import combdrive_fmu_path, core_library_path, fmu_path
from .compare import Comparison, compare
from .cosim import CosimError, cosimulate
from .fmu_runner import SimulationError
from .moreau import moreau
from .results import Trajectory
from .scene import IntegratorSettings, Scene, SceneError, load_scene, scene_from_dict
from .simulate import simulate

__all__ = [
    "Comparison",
    "CosimError",
    "IntegratorSettings",
    "Scene",
    "SceneError",
    "SimulationError",
    "Trajectory",
    "combdrive_fmu_path",
    "compare",
    "core_library_path",
    "cosimulate",
    "fmu_path",
    "load_scene",
    "moreau",
    "scene_from_dict",
    "simulate",
]
__version__ = "0.1.0"
