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
