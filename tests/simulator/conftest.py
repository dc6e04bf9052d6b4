"""Fixtures of the simulator tests."""

from __future__ import annotations

import uuid
from collections.abc import Iterator

import pytest

from tests.simulator.recorder import Recorder


@pytest.fixture
def recorder() -> Iterator[Recorder]:
    """A subscriber on a fresh interface name; clears AGV-1/AGV-2 retained topics after."""
    rec = Recorder(f"simtest{uuid.uuid4().hex[:10]}")
    yield rec
    rec.close(["AGV-1", "AGV-2"])


@pytest.fixture
def recorder3() -> Iterator[Recorder]:
    """Like ``recorder``, for 3.0 vehicles: subscribes to ``<interface>/v3/...``."""
    rec = Recorder(f"simtest{uuid.uuid4().hex[:10]}", major="v3")
    yield rec
    rec.close(["AGV-1", "AGV-2"])
