"""Reads of alerts: open ones for the banner and list, history and counts for reports."""

from datetime import datetime

from django.db.models import Count, QuerySet

from alerts.models import SEVERITY_RANK, Alert


def open_alerts() -> QuerySet[Alert]:
    return Alert.objects.exclude(status=Alert.Status.RESOLVED).select_related("vehicle")


def banner() -> dict[str, object]:
    """What the live banner shows: counts by severity and the worst few open alerts."""
    alerts = list(open_alerts().order_by("-raised_at")[:200])
    alerts.sort(key=lambda a: (-SEVERITY_RANK[a.severity], a.status != Alert.Status.OPEN))
    counts: dict[str, int] = {}
    for alert in alerts:
        counts[alert.severity] = counts.get(alert.severity, 0) + 1
    return {
        "open": len(alerts),
        "unacknowledged": sum(1 for a in alerts if a.status == Alert.Status.OPEN),
        "by_severity": counts,
        "top": [
            {
                "id": a.pk,
                "severity": a.severity,
                "status": a.status,
                "message": a.message,
                "vehicle": str(a.vehicle) if a.vehicle else None,
                "raised_at": a.raised_at.isoformat(),
            }
            for a in alerts[:5]
        ],
    }


def counts(*, since: datetime, until: datetime) -> list[dict[str, object]]:
    """Alerts raised in [since, until) by source and severity (for reports)."""
    return list(
        Alert.objects.filter(raised_at__gte=since, raised_at__lt=until)
        .values("source", "severity")
        .annotate(raised=Count("pk"))
        .order_by("source", "severity")
    )


def history(*, since: datetime, until: datetime) -> QuerySet[Alert]:
    return Alert.objects.filter(raised_at__gte=since, raised_at__lt=until).select_related("vehicle")
