"""The version of csfh, in one place: the Python package, its wheel metadata (pyproject.toml),
the CMake project and both FMUs' modelDescription.xml read it from this file."""

__version__ = "0.2.0"
