"""Fixtures shared by the Django app tests."""

from collections.abc import Iterator

import pytest

from maps.demo import warehouse_layout
from maps.models import Map
from maps.services import create_layout
from tests.e2e.processes import Process


@pytest.fixture
def demo_map(db: None) -> Map:
    """The demo warehouse: 6 × 4 aisle grid with stations on spurs."""
    return create_layout(spec=warehouse_layout(columns=6, rows=4))


@pytest.fixture
def stop_all() -> Iterator[list[Process]]:
    """Processes appended here are stopped (SIGTERM) after the test, whatever happened."""
    processes: list[Process] = []
    yield processes
    for process in processes:
        process.terminate()
