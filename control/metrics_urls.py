"""`/metrics` (included from fleet.urls: the Prometheus scrape path has no prefix)."""

from django.urls import path

from control import prometheus

urlpatterns = [path("", prometheus.metrics, name="metrics")]
