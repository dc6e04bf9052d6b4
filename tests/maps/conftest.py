"""Fixtures of the maps tests."""

import pytest
from django.contrib.auth import get_user_model
from rest_framework.test import APIClient

from maps.selectors import clear_graph_cache


@pytest.fixture(autouse=True)
def _fresh_graph_cache() -> None:
    clear_graph_cache()


@pytest.fixture
def staff(db: None):
    return get_user_model().objects.create_user(
        "planner", password="pw", is_staff=True, is_superuser=True
    )


@pytest.fixture
def api(staff) -> APIClient:
    client = APIClient()
    client.force_authenticate(staff)
    return client
