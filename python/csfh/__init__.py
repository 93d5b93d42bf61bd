"""csfh: dynamics of a Conjugate-Surface Flexure Hinge with impacts and friction.

The model is an FMI 2.0 FMU (model exchange and co-simulation) built from the C core in
``fmu_src/``; this package ships it and adds scenes, a Moreau time stepper, comparisons and
reports on top.
"""

from __future__ import annotations

from ._paths import fmu_path

__all__ = ["fmu_path"]
__version__ = "0.1.0"
