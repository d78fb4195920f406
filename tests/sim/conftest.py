"""Fixtures of the simulation tests."""

from __future__ import annotations

import pytest

import sim


@pytest.fixture(scope="session")
def backend() -> str:
    """The offscreen GL backend the rendering tests draw with (they skip without one)."""
    try:
        return sim.resolve_backend()
    except sim.GLUnavailableError as exc:  # only where no GL backend exists at all
        pytest.skip(f"no offscreen GL backend: {exc}")
