"""csfh: dynamics of a Conjugate-Surface Flexure Hinge with impacts and friction.

The model is an FMI 2.0 FMU (model exchange and co-simulation) built from the C core in
``fmu_src/``; this package ships it, with the same core as a shared library, and adds scenes,
the Moreau time stepper, comparisons and reports on top.

    >>> import csfh
    >>> scene = csfh.load_scene("csfh")
    >>> run = csfh.simulate(scene, "LN_cylinders")      # FMU, model exchange, CVode
    >>> rigid = csfh.moreau(scene, stick_rule="memory")  # Moreau midpoint stepper
    >>> driven = csfh.cosimulate(csfh.load_scene("combdrive"))  # with the comb-drive FMU
    >>> system = csfh.ssp_path("combdrive")  # the same coupled system as an SSP 1.0 file

The model itself is documented in ``docs/model.md``.

The package, by role (each layer imports only the ones below it; tests/tools/test_layout.py
checks it):

* ``csfh.cli``: the command line;
* ``csfh.studies``: the paper's comparison, accuracy, stress, sweep, tolerance, shock and design
  studies, each with its report;
* ``csfh.cosim``: co-simulation of the hinge with the comb-drive actuator;
* ``csfh.batch``: many runs of one scene (tasks, result store, executors);
* ``csfh.runners``: one run of one model (the FMU, Moreau, RK4) -> a `Trajectory`, and batches
  of runs (Moreau in the C core, co-simulation in the FMU's own binary), behind one protocol
  (``csfh.runners.registry``);
* ``csfh.model``: what the model is (the FMUs' interfaces, presets, scenes, the C core);
* foundation: ``errors`` (what a user is told: csfh.CsfhError and its kinds), ``paths`` (where
  the binaries are), ``trajectory``, ``output`` (every file written), ``progress``,
  ``plotting``.

The names below are imported on first use, so that ``import csfh`` (and ``csfh --help``) stays
fast.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

from ._version import __version__

if TYPE_CHECKING:
    from .cosim.coupling import CosimError
    from .cosim.run import cosimulate
    from .cosim.ssp import ssp_path, write_ssp
    from .errors import CsfhError, ParameterError, SceneError, SimulationError
    from .model.scene import IntegratorSettings, Scene, load_scene, scene_from_dict
    from .paths import batch_library_path, combdrive_fmu_path, core_library_path, fmu_path
    from .runners.cs_batch import CsBatchResult, cs_batch
    from .runners.moreau import moreau
    from .runners.simulate import simulate
    from .studies.compare import Comparison, compare
    from .studies.design.run import design
    from .studies.linearize.result import Linearization
    from .studies.linearize.run import linearize
    from .trajectory import Trajectory

_PUBLIC = {
    "Comparison": "csfh.studies.compare",
    "CosimError": "csfh.cosim.coupling",
    "CsBatchResult": "csfh.runners.cs_batch",
    "CsfhError": "csfh.errors",
    "IntegratorSettings": "csfh.model.scene",
    "Linearization": "csfh.studies.linearize.result",
    "ParameterError": "csfh.errors",
    "Scene": "csfh.model.scene",
    "SceneError": "csfh.errors",
    "SimulationError": "csfh.errors",
    "Trajectory": "csfh.trajectory",
    "batch_library_path": "csfh.paths",
    "combdrive_fmu_path": "csfh.paths",
    "compare": "csfh.studies.compare",
    "core_library_path": "csfh.paths",
    "cosimulate": "csfh.cosim.run",
    "cs_batch": "csfh.runners.cs_batch",
    "design": "csfh.studies.design.run",
    "fmu_path": "csfh.paths",
    "linearize": "csfh.studies.linearize.run",
    "load_scene": "csfh.model.scene",
    "moreau": "csfh.runners.moreau",
    "scene_from_dict": "csfh.model.scene",
    "simulate": "csfh.runners.simulate",
    "ssp_path": "csfh.cosim.ssp",
    "write_ssp": "csfh.cosim.ssp",
}
"""Each public name and the module that defines it."""

__all__ = [
    "Comparison",
    "CosimError",
    "CsBatchResult",
    "CsfhError",
    "IntegratorSettings",
    "Linearization",
    "ParameterError",
    "Scene",
    "SceneError",
    "SimulationError",
    "Trajectory",
    "__version__",
    "batch_library_path",
    "combdrive_fmu_path",
    "compare",
    "core_library_path",
    "cosimulate",
    "cs_batch",
    "design",
    "fmu_path",
    "linearize",
    "load_scene",
    "moreau",
    "scene_from_dict",
    "simulate",
    "ssp_path",
    "write_ssp",
]


def __getattr__(name: str) -> Any:
    module = _PUBLIC.get(name)
    if module is None:
        raise AttributeError(f"module 'csfh' has no attribute {name!r}")
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value  # next time without __getattr__
    return value


def __dir__() -> list[str]:
    return sorted({*globals(), *__all__})
