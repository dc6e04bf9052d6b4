"""The Celery application: dispatch, persistence batches, alerts, reports, webhooks."""

import os
from typing import Any

from celery import Celery
from celery.signals import worker_process_init

os.environ.setdefault("DJANGO_SETTINGS_MODULE", "fleet.settings")

app = Celery("fleet")
app.config_from_object("django.conf:settings", namespace="CELERY")
app.autodiscover_tasks()


@worker_process_init.connect
def keep_database_connections(**_kwargs: Any) -> None:
    """A pool process keeps its database connection for WORKER_DB_CONN_MAX_AGE seconds.

    The web closes its connections after each request (DB_CONN_MAX_AGE, 0: daphne's thread
    pool would pile them up); a pool process runs one task at a time, so one connection each is
    safe, and reconnecting for every task cost each dispatch cycle a connection setup (the
    load benchmark's worker profile, docs/LOAD.md eleventh round). Celery's Django fix-up still
    closes a connection after a task when it is broken or older than that.
    """
    from django.conf import settings
    from django.db import connections

    if settings.DATABASES["default"]["ENGINE"] != "django.db.backends.sqlite3":
        connections.settings["default"]["CONN_MAX_AGE"] = settings.WORKER_DB_CONN_MAX_AGE
