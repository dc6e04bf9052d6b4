"""The alert service contract, the alert list (acknowledge/resolve with a comment), the banner
feed, counts for reports, and VDA 5050 3.0 severities."""

from datetime import timedelta

import pytest
from django.utils import timezone

from alerts import selectors
from alerts.models import Alert, Severity, Source
from alerts.services import raise_alert, resolve_alert
from alerts.services.observe import SnapshotObserver
from fleet.exceptions import InvalidRequestError
from robots.models import Vehicle
from tests.factories import user_with_role

pytestmark = pytest.mark.django_db


def test_raising_the_same_cause_twice_keeps_one_open_alert() -> None:
    first = raise_alert(cause="maintenance:7", source=Source.MAINTENANCE, message="service due")
    again = raise_alert(
        cause="maintenance:7",
        source=Source.MAINTENANCE,
        severity=Severity.URGENT,
        message="overdue",
    )

    assert again.pk == first.pk
    assert again.occurrences == 2
    assert again.severity == Severity.URGENT
    assert again.message == "overdue"
    assert resolve_alert("maintenance:7").auto_resolved
    assert resolve_alert("maintenance:7") is None  # nothing open any more
    reopened = raise_alert(cause="maintenance:7", source=Source.MAINTENANCE, message="due again")
    assert reopened.pk != first.pk
    assert Alert.objects.count() == 2


@pytest.mark.parametrize(
    "kwargs",
    [{"severity": "LOUD"}, {"source": "GOSSIP"}, {"cause": ""}],
)
def test_a_malformed_alert_is_refused(kwargs) -> None:
    with pytest.raises(InvalidRequestError):
        raise_alert(**{"cause": "x:1", "message": "m", **kwargs})
    assert Alert.objects.count() == 0


@pytest.mark.parametrize("level", ["WARNING", "URGENT", "CRITICAL", "FATAL"])
def test_vda5050_3_error_levels_keep_their_severity(level) -> None:
    vehicle = Vehicle.objects.create(manufacturer="sim", serial_number="AGV-1")
    snapshot = {"pk": vehicle.pk, "errors": [{"errorType": "x", "errorLevel": level}]}

    SnapshotObserver().observe([snapshot])

    assert Alert.objects.get().severity == level


def test_the_list_needs_a_login_and_a_resolve_needs_a_comment(client, django_user_model) -> None:
    alert = raise_alert(cause="battery:1", source=Source.BATTERY, message="battery at 12 %")
    assert client.get("/alerts/").status_code == 302
    assert client.get("/alerts/banner.json").status_code == 302
    user = user_with_role("operator", "ops", password="pw")
    client.force_login(user)

    page = client.get("/alerts/")
    assert "battery at 12 %" in page.content.decode()
    assert client.get("/alerts/banner.json").json()["unacknowledged"] == 1

    client.post(f"/alerts/{alert.pk}/acknowledge/", {"comment": "driving it to a charger"})
    alert.refresh_from_db()
    assert alert.status == Alert.Status.ACKNOWLEDGED
    assert alert.acknowledged_by == user
    assert client.get("/alerts/banner.json").json()["unacknowledged"] == 0

    client.post(f"/alerts/{alert.pk}/resolve/", {"comment": "  "})
    alert.refresh_from_db()
    assert alert.status == Alert.Status.ACKNOWLEDGED  # refused without a comment

    client.post(f"/alerts/{alert.pk}/resolve/", {"comment": "charged"})
    alert.refresh_from_db()
    assert alert.status == Alert.Status.RESOLVED
    assert alert.resolve_comment == "charged"
    assert client.get("/alerts/banner.json").json()["open"] == 0


def test_counts_for_reports_by_source_and_severity() -> None:
    raise_alert(cause="a", source=Source.BATTERY, message="m")
    raise_alert(cause="b", source=Source.BATTERY, message="m")
    raise_alert(cause="c", source=Source.PROTOCOL, severity=Severity.INFO, message="m")
    now = timezone.now()

    rows = selectors.counts(since=now - timedelta(hours=1), until=now + timedelta(seconds=1))

    assert rows == [
        {"source": "BATTERY", "severity": "WARNING", "raised": 2},
        {"source": "PROTOCOL", "severity": "INFO", "raised": 1},
    ]
