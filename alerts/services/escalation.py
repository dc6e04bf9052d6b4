"""Escalation: tell someone when an alert stays unacknowledged too long (run by Celery beat)."""

import json
import logging
import urllib.request
from datetime import timedelta

from django.conf import settings
from django.core.mail import send_mail
from django.db import IntegrityError, transaction
from django.utils import timezone

from alerts import conf
from alerts.models import SEVERITY_RANK, Alert, AlertNotification, EscalationRule

logger = logging.getLogger(__name__)


def escalate_alerts() -> int:
    """Notify every active rule's recipients about the OPEN alerts that waited long enough.

    An alert counts from `raised_at`; ACKNOWLEDGED and RESOLVED alerts never escalate. Each
    (alert, rule) pair is notified once: the notification row is claimed by a unique insert
    before anything is sent, so two beat runs racing each other send one message. Returns the
    number of notifications made.
    """
    now = timezone.now()
    sent = 0
    for rule in EscalationRule.objects.filter(active=True):
        severities = [
            s for s, rank in SEVERITY_RANK.items() if rank >= SEVERITY_RANK[rule.min_severity]
        ]
        due = Alert.objects.filter(
            status=Alert.Status.OPEN,
            severity__in=severities,
            raised_at__lte=now - timedelta(minutes=rule.after_minutes),
        ).exclude(notifications__rule=rule)
        if rule.source:
            due = due.filter(source=rule.source)
        for alert in due.select_related("vehicle")[:200]:
            try:
                with transaction.atomic():
                    notification = AlertNotification.objects.create(alert=alert, rule=rule)
            except IntegrityError:
                continue  # another run claimed it
            _notify(notification, alert, rule)
            sent += 1
    return sent


def _payload(alert: Alert, rule: EscalationRule) -> dict[str, object]:
    return {
        "event": "alert.escalated",
        "rule": rule.name,
        "alert": {
            "id": alert.pk,
            "cause": alert.cause,
            "source": alert.source,
            "severity": alert.severity,
            "status": alert.status,
            "vehicle": str(alert.vehicle) if alert.vehicle else None,
            "order": alert.order_ref or None,
            "message": alert.message,
            "raised_at": alert.raised_at.isoformat(),
            "occurrences": alert.occurrences,
        },
    }


def _notify(notification: AlertNotification, alert: Alert, rule: EscalationRule) -> None:
    errors: list[str] = []
    recipients = rule.recipients()
    if recipients:
        try:
            send_mail(
                subject=f"[fleet] {alert.severity} alert unacknowledged: {alert.message[:80]}",
                message=(
                    f"{alert.message}\n\nsource: {alert.get_source_display()}\n"
                    f"vehicle: {alert.vehicle or '-'}\norder: {alert.order_ref or '-'}\n"
                    f"raised: {alert.raised_at:%Y-%m-%d %H:%M:%S %Z}, {alert.occurrences}×\n"
                    f"rule: {rule}\n"
                ),
                from_email=getattr(settings, "DEFAULT_FROM_EMAIL", None),
                recipient_list=recipients,
            )
            notification.email_sent = True
        except Exception as exc:  # a mail server being down must not stop the webhook
            logger.warning("escalation email for alert %s failed: %s", alert.pk, exc)
            errors.append(f"email: {exc}")
    if rule.webhook_url:
        try:
            notification.webhook_status = _post(rule.webhook_url, _payload(alert, rule))
        except Exception as exc:
            logger.warning("escalation webhook for alert %s failed: %s", alert.pk, exc)
            errors.append(f"webhook: {exc}")
    notification.error = "; ".join(errors)
    notification.save(update_fields=["email_sent", "webhook_status", "error"])


def _post(url: str, payload: dict[str, object]) -> int:
    if not url.startswith(("http://", "https://")):
        raise ValueError(f"not an http(s) URL: {url}")
    request = urllib.request.Request(  # noqa: S310 (http(s) only, checked above)
        url,
        data=json.dumps(payload).encode(),
        headers={"Content-Type": "application/json", "User-Agent": "open-fleet-alerts"},
        method="POST",
    )
    timeout = conf.webhook_timeout_seconds()
    with urllib.request.urlopen(request, timeout=timeout) as response:  # noqa: S310 (checked above)
        return int(response.status)
