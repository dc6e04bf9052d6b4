"""Escalation: an alert unacknowledged past a rule's minutes is emailed and posted once;
an acknowledged one is not."""

import json
import threading
from datetime import timedelta
from http.server import BaseHTTPRequestHandler, HTTPServer

import pytest
from django.core import mail
from django.utils import timezone

from alerts.models import Alert, AlertNotification, EscalationRule, Severity, Source
from alerts.services import acknowledge_alert, escalate_alerts
from vda5050.enums import ErrorLevel

pytestmark = pytest.mark.django_db(transaction=True)


@pytest.fixture
def webhook():
    received: list[dict] = []

    class Handler(BaseHTTPRequestHandler):
        def do_POST(self) -> None:  # noqa: N802 (http.server's name)
            received.append(json.loads(self.rfile.read(int(self.headers["Content-Length"]))))
            self.send_response(204)
            self.end_headers()

        def log_message(self, *args: object) -> None:
            pass

    server = HTTPServer(("127.0.0.1", 0), Handler)
    threading.Thread(target=server.serve_forever, daemon=True).start()
    yield f"http://127.0.0.1:{server.server_port}/hook", received
    server.shutdown()


def test_a_simulated_fatal_error_escalates_once_by_email_and_webhook(make_harness, webhook) -> None:
    url, received = webhook
    EscalationRule.objects.create(
        name="shift lead",
        min_severity=Severity.URGENT,
        after_minutes=5,
        email_to="lead@example.com, ops@example.com",
        webhook_url=url,
    )
    harness = make_harness()
    harness.vehicle().inject_error("emergencyStop", ErrorLevel.FATAL)
    harness.step(1)
    (alert,) = Alert.objects.filter(source=Source.VDA_ERROR)

    assert escalate_alerts() == 0  # not yet 5 minutes
    Alert.objects.filter(pk=alert.pk).update(raised_at=timezone.now() - timedelta(minutes=6))
    assert escalate_alerts() == 1
    assert escalate_alerts() == 0  # once per rule and alert

    assert len(mail.outbox) == 1
    assert mail.outbox[0].to == ["lead@example.com", "ops@example.com"]
    assert "emergencyStop" in mail.outbox[0].body
    assert [r["alert"]["cause"] for r in received] == [alert.cause]
    notification = AlertNotification.objects.get()
    assert notification.email_sent
    assert notification.webhook_status == 204

    harness.vehicle().clear_injected_errors()
    harness.step(1)
    alert.refresh_from_db()
    assert alert.status == Alert.Status.RESOLVED
    assert alert.auto_resolved


def test_an_acknowledged_or_too_mild_alert_does_not_escalate(
    make_harness, django_user_model
) -> None:
    EscalationRule.objects.create(
        name="r", min_severity=Severity.CRITICAL, after_minutes=1, email_to="lead@example.com"
    )
    harness = make_harness()
    harness.vehicle().inject_error("scanner", ErrorLevel.WARNING)
    harness.vehicle().inject_error("bumper", ErrorLevel.FATAL)
    harness.step(1)
    Alert.objects.update(raised_at=timezone.now() - timedelta(minutes=2))
    fatal = Alert.objects.get(cause__endswith=":bumper")
    acknowledge_alert(
        alert_id=fatal.pk, user=django_user_model.objects.create_user("u"), comment="on it"
    )

    assert escalate_alerts() == 0
    assert mail.outbox == []


def test_beat_runs_the_escalation_task(settings) -> None:
    from alerts.tasks import escalate_alerts_task

    EscalationRule.objects.create(
        name="r", min_severity=Severity.WARNING, after_minutes=0, email_to="lead@example.com"
    )
    Alert.objects.create(cause="battery:1", source=Source.BATTERY, message="battery at 9 %")

    assert settings.CELERY_BEAT_SCHEDULE["alerts-escalate"]["task"] == escalate_alerts_task.name
    assert escalate_alerts_task.apply().get() == 1
    assert len(mail.outbox) == 1
