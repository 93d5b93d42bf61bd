"""The built-in scenes: the TOML files of this directory, which csfh.load_scene takes by name.
The tolerance_*.toml files are the tolerance study's (csfh.studies.tolerance): a scene with its
[tolerance] and [montecarlo] tables, taken by that study, not by load_scene."""

from importlib import resources

TOLERANCE_PREFIX = "tolerance_"
"""The names of the tolerance study's files."""
BUILTIN_SCENES = tuple(
    sorted(
        entry.name.removesuffix(".toml")
        for entry in resources.files(__package__).iterdir()
        if entry.name.endswith(".toml") and not entry.name.startswith(TOLERANCE_PREFIX)
    )
)
"""The scenes csfh.load_scene takes by name (combdrive: the co-simulation of `csfh cosim`)."""
