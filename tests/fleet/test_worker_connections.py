"""Celery pool processes keep their database connection between tasks (fleet/celery.py)."""

import pytest
from celery.signals import worker_process_init
from django.conf import settings
from django.db import connections

import fleet.celery  # noqa: F401  (connects the signal handler)


def test_a_pool_process_keeps_its_database_connection_between_tasks(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    if connections["default"].vendor == "sqlite":
        pytest.skip("the embedded default runs tasks eagerly in the web process")
    monkeypatch.setitem(connections.settings["default"], "CONN_MAX_AGE", 0)  # as the web has it

    worker_process_init.send(sender=None)

    assert settings.WORKER_DB_CONN_MAX_AGE > 0
    assert connections.settings["default"]["CONN_MAX_AGE"] == settings.WORKER_DB_CONN_MAX_AGE
    assert connections["default"].settings_dict["CONN_MAX_AGE"] == settings.WORKER_DB_CONN_MAX_AGE
