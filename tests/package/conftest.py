"""Fixtures of the package's tests."""

from __future__ import annotations

import pytest


@pytest.fixture
def libcosim() -> None:
    """The libcosimpy engine (installed by tools/setup.sh: pip install .[cosim])."""
    pytest.importorskip("libcosimpy")
