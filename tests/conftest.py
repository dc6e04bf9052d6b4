"""Fixtures shared by the Django app tests."""

import pytest

from maps.demo import warehouse_layout
from maps.models import Map
from maps.services import create_layout


@pytest.fixture
def demo_map(db: None) -> Map:
    """The demo warehouse: 6 × 4 aisle grid with stations on spurs."""
    return create_layout(spec=warehouse_layout(columns=6, rows=4))
