"""Cross-cutting pytest configuration: report which services the run uses."""

from django.conf import settings


def pytest_report_header() -> list[str]:
    services = getattr(settings, "SERVICES", {})
    return ["services: " + ", ".join(f"{name}={url}" for name, url in services.items())]
