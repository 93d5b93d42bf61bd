"""The built-in scenes: the TOML files of this directory, which csfh.load_scene takes by name (the
tolerance_*.toml files are the tolerance study's, csfh.studies.tolerance)."""

BUILTIN_SCENES = ("central", "asymmetric", "csfh", "mems", "combdrive")
"""The scenes csfh.load_scene takes by name (combdrive: the co-simulation of `csfh cosim`)."""
