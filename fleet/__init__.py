"""The Django project: settings, URL and ASGI routing, Celery app and cross-app helpers."""

from fleet.celery import app as celery_app

__all__ = ["celery_app"]
