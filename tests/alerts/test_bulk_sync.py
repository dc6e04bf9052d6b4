"""A fleet-wide event raises or clears an alert on every vehicle at once (issue 11): that costs
a few statements, not a savepoint, a select and an insert per alert."""

import pytest
from django.db import connection
from django.test.utils import CaptureQueriesContext

from alerts.models import Alert, Severity, Source
from alerts.services import core, raise_alert, sync_causes
from fleet.exceptions import InvalidRequestError
from robots.models import Vehicle

pytestmark = pytest.mark.django_db


def _timeouts(vehicles: list[Vehicle]) -> dict[str, dict[str, object]]:
    return {
        f"state_timeout:{v.pk}": {
            "source": Source.STATE_TIMEOUT,
            "severity": Severity.URGENT,
            "message": "no state within the vehicle's state interval",
            "vehicle": v.pk,
            "order_ref": "TO-1",
            "details": {"n": v.pk},
        }
        for v in vehicles
    }


def test_six_hundred_alerts_open_and_clear_in_a_few_statements() -> None:
    vehicles = [
        Vehicle.objects.create(manufacturer="sim", serial_number=f"AGV-{i}") for i in range(600)
    ]
    active = _timeouts(vehicles)
    with CaptureQueriesContext(connection) as opened:
        assert sync_causes(prefixes=["state_timeout:"], active=active) == (600, 0)
    with CaptureQueriesContext(connection) as unchanged:
        assert sync_causes(prefixes=["state_timeout:"], active=active) == (0, 0)
    with CaptureQueriesContext(connection) as cleared:
        assert sync_causes(prefixes=["state_timeout:"], active={}) == (0, 600)

    assert len(opened) <= 6  # read open causes, savepoint, 2 INSERTs of 500, release
    assert len(unchanged) == 1
    assert len(cleared) <= 3  # read, 2 UPDATEs of 500
    first = Alert.objects.get(cause=f"state_timeout:{vehicles[0].pk}")
    assert (first.source, first.severity, first.vehicle_id) == (
        Source.STATE_TIMEOUT,
        Severity.URGENT,
        vehicles[0].pk,
    )
    assert (first.order_ref, first.details, first.occurrences) == ("TO-1", {"n": vehicles[0].pk}, 1)
    assert first.status == Alert.Status.RESOLVED
    assert first.auto_resolved
    assert first.resolved_at is not None
    assert first.resolved_by is None
    assert not Alert.objects.exclude(status=Alert.Status.RESOLVED).exists()


def test_a_cause_opened_meanwhile_by_another_process_stays_one_alert() -> None:
    vehicle = Vehicle.objects.create(manufacturer="sim", serial_number="AGV-1")
    active = _timeouts([vehicle])
    raise_alert(cause=f"state_timeout:{vehicle.pk}", message="raced", source=Source.STATE_TIMEOUT)
    # As if read before the other process inserted: the bulk insert must skip, not fail.
    core._open_many(active)
    assert Alert.objects.filter(cause=f"state_timeout:{vehicle.pk}").count() == 1


def test_an_unknown_severity_is_refused() -> None:
    with pytest.raises(InvalidRequestError):
        sync_causes(prefixes=["x:"], active={"x:1": {"message": "m", "severity": "BAD"}})
