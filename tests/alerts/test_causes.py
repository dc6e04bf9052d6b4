"""Issue 8 acceptance: each alert cause, driven with the simulator through control's flush,
is raised, deduplicated (one open alert per cause) and auto-resolved when the cause clears."""

import pytest
from django.test import override_settings

from alerts.models import Alert, Severity, Source
from alerts.services import resolve_by_user
from maps.models import Station
from orders.models import TransportOrder
from orders.services import create_transport_order, dispatch_pending_orders, floor
from robots.models import Vehicle
from simulator import wire
from simulator.misbehaviour import Misbehaviour
from vda5050.enums import ConnectionState, ErrorLevel, TopicKind

pytestmark = pytest.mark.django_db(transaction=True)  # the store closes stale connections


def alerts(source: str) -> list[Alert]:
    return list(Alert.objects.filter(source=source).order_by("pk"))


def open_alerts(source: str) -> list[Alert]:
    return [a for a in alerts(source) if a.is_open]


@pytest.mark.parametrize("version", ["2.0.0", "3.0.0"])
@pytest.mark.parametrize("level", [ErrorLevel.WARNING, ErrorLevel.FATAL])
def test_a_vehicle_error_raises_once_and_resolves_when_cleared(
    make_harness, version, level
) -> None:
    harness = make_harness(version=version)
    agv = harness.vehicle()
    agv.inject_error("laserScannerBlocked", level, "scanner dirty")
    harness.step(2)
    harness.step(2)  # the same error in several states and flushes

    raised = open_alerts(Source.VDA_ERROR)
    assert len(raised) == 1
    assert raised[0].severity == str(level.value)
    assert raised[0].vehicle == Vehicle.objects.get(serial_number="AGV-1")
    assert "laserScannerBlocked" in raised[0].message

    agv.clear_injected_errors()
    harness.step(1)

    (alert,) = alerts(Source.VDA_ERROR)
    assert alert.status == Alert.Status.RESOLVED
    assert alert.auto_resolved


def test_connection_broken_raises_and_resolves_on_reconnect(make_harness) -> None:
    harness = make_harness()
    agv = harness.vehicle()
    harness.silent.add("AGV-1")
    harness.send(agv, TopicKind.CONNECTION, wire.connection(agv, ConnectionState.CONNECTIONBROKEN))
    harness.step(1)
    harness.step(1)

    (alert,) = open_alerts(Source.CONNECTION)
    assert alert.severity == Severity.URGENT

    harness.silent.discard("AGV-1")
    harness.send(agv, TopicKind.CONNECTION, wire.connection(agv, ConnectionState.ONLINE))
    harness.step(1)

    assert open_alerts(Source.CONNECTION) == []
    assert alerts(Source.CONNECTION)[0].auto_resolved


def test_a_silent_vehicle_raises_a_state_timeout_until_it_speaks_again(make_harness) -> None:
    harness = make_harness()
    harness.silent.add("AGV-1")
    harness.step(40)  # default state interval 30 s + 5 s grace

    assert len(open_alerts(Source.STATE_TIMEOUT)) == 1
    harness.step(5)
    assert len(alerts(Source.STATE_TIMEOUT)) == 1  # deduplicated

    harness.silent.discard("AGV-1")
    harness.step(1)
    assert open_alerts(Source.STATE_TIMEOUT) == []


def test_low_battery_warns_turns_critical_and_resolves_above_the_hysteresis(make_harness) -> None:
    harness = make_harness()
    agv = harness.vehicle()
    agv.battery = 15
    harness.step(1)
    (alert,) = open_alerts(Source.BATTERY)
    assert alert.severity == Severity.WARNING

    agv.battery = 8
    harness.step(1)
    (alert,) = open_alerts(Source.BATTERY)
    assert alert.severity == Severity.CRITICAL  # the same alert, raised in severity

    agv.battery = 22  # above 20 % but inside the 5 % hysteresis: still low
    harness.step(1)
    assert len(open_alerts(Source.BATTERY)) == 1

    agv.battery = 40
    harness.step(1)
    assert open_alerts(Source.BATTERY) == []
    assert len(alerts(Source.BATTERY)) == 1


def _order(harness, **fields) -> TransportOrder:
    pick = Station.objects.filter(kind=Station.Kind.PICK).order_by("station_id").first()
    drop = Station.objects.filter(kind=Station.Kind.DROP).order_by("station_id").first()
    order = create_transport_order(source=pick, destination=drop, **fields)
    dispatch_pending_orders()
    fresh = TransportOrder.objects.get(pk=order.pk)
    assert fresh.vehicle is not None, (
        fresh.dispatch_note,
        list(
            Vehicle.objects.values(
                "connection", "operating_mode", "map_id", "last_node_id", "errors"
            )
        ),
    )
    return order


@override_settings(ALERTS_NO_PROGRESS_SECONDS=60)
def test_a_vehicle_stuck_on_its_order_raises_no_progress_until_it_moves(make_harness) -> None:
    harness = make_harness()
    agv = harness.vehicle()
    order = _order(harness)
    harness.run_until(lambda: agv.has_order, limit=30)
    agv.paused = True  # stands still with its order (blocked by an obstacle, say)
    for _ in range(14):
        harness.step(5)  # flushes every 5 simulated seconds
    (alert,) = open_alerts(Source.NO_PROGRESS)
    assert alert.order_ref == TransportOrder.objects.get(pk=order.pk).vda_order_id
    harness.step(5)
    harness.step(5)
    assert len(alerts(Source.NO_PROGRESS)) == 1

    agv.paused = False
    harness.step(2)
    assert open_alerts(Source.NO_PROGRESS) == []


def test_a_rejected_order_raises_an_order_failed_alert_closed_by_a_person(
    make_harness, django_user_model
) -> None:
    harness = make_harness()
    harness.vehicle().misbehave(Misbehaviour(reject_orders="orderError"))
    order = _order(harness, external_ref="ERP-42")
    harness.run_until(
        lambda: TransportOrder.objects.get(pk=order.pk).status == TransportOrder.Status.FAILED,
        limit=60,
    )
    harness.step(2)

    (alert,) = alerts(Source.ORDER_FAILED)
    assert alert.order_ref == "ERP-42"
    assert alert.severity == Severity.URGENT
    # A failed order is an event, not a condition: a person closes it, with a comment.
    user = django_user_model.objects.create_user("ops", password="x")
    resolve_by_user(alert_id=alert.pk, user=user, comment="pallet re-stacked, order re-sent")
    alert.refresh_from_db()
    assert alert.status == Alert.Status.RESOLVED
    assert not alert.auto_resolved
    assert alert.resolved_by == user


def test_an_order_past_its_deadline_raises_late_and_resolves_when_finished(make_harness) -> None:
    from datetime import timedelta

    from django.utils import timezone

    harness = make_harness()
    order = _order(harness, deadline=timezone.now() + timedelta(seconds=1))
    TransportOrder.objects.filter(pk=order.pk).update(
        deadline=timezone.now() - timedelta(seconds=1)
    )
    floor.LATE_CHECK_SECONDS = 0  # the flush hook checks deadlines every 30 s; here every flush
    harness.step(1)
    (alert,) = open_alerts(Source.ORDER_LATE)
    assert alert.order_ref == f"TO-{order.pk}"

    harness.run_until(
        lambda: TransportOrder.objects.get(pk=order.pk).status == TransportOrder.Status.FINISHED,
        limit=240,
    )
    assert len(alerts(Source.ORDER_LATE)) == 1
    assert open_alerts(Source.ORDER_LATE) == []


@override_settings(ALERTS_PROTOCOL_QUIET_SECONDS=30)
def test_malformed_messages_raise_a_protocol_alert_that_resolves_when_quiet(make_harness) -> None:
    harness = make_harness()
    agv = harness.vehicle()
    harness.step(1)
    topic = harness.topic(agv, "state")
    harness.controller.handle_message(topic, b'{"headerId": "not a state"')
    harness.step(1)
    harness.controller.handle_message(topic, b"garbage")
    harness.step(1)

    (alert,) = open_alerts(Source.PROTOCOL)
    assert "malformed" in alert.message or alert.details["counters"]

    harness.step(35)
    assert open_alerts(Source.PROTOCOL) == []


def test_due_maintenance_raises_until_work_starts(make_harness) -> None:
    from datetime import timedelta

    from django.utils import timezone

    from maintenance.models import WorkOrder

    harness = make_harness()
    floor.LATE_CHECK_SECONDS = 0
    vehicle = Vehicle.objects.get(serial_number="AGV-1")
    work = WorkOrder.objects.create(
        vehicle=vehicle,
        title="brake check",
        status=WorkOrder.Status.DUE,
        due_at=timezone.now() - timedelta(minutes=1),
    )
    harness.step(1)
    harness.step(1)

    (alert,) = open_alerts(Source.MAINTENANCE)
    assert alert.vehicle == vehicle
    assert "brake check" in alert.message

    WorkOrder.objects.filter(pk=work.pk).update(status=WorkOrder.Status.IN_PROGRESS)
    harness.step(1)
    assert open_alerts(Source.MAINTENANCE) == []
    assert len(alerts(Source.MAINTENANCE)) == 1


def test_a_service_plan_fired_by_simulated_driving_raises_a_maintenance_alert(
    make_harness,
) -> None:
    from maintenance import services as maintenance
    from maintenance.models import ServicePlan, WorkOrder
    from maintenance.services.observe import OBSERVER

    OBSERVER.tracks.clear()  # the counters' memory belongs to this test's vehicles
    harness = make_harness()
    ServicePlan.objects.create(name="Wheel check", interval_km=0.01)  # every 10 m driven
    assert maintenance.check_service_plans() == []  # the baseline: nothing driven yet
    order = _order(harness)

    harness.run_until(
        lambda: TransportOrder.objects.get(pk=order.pk).status == TransportOrder.Status.FINISHED,
        limit=240,
    )
    OBSERVER.flush_all()  # the counters the simulated drive added
    (work,) = maintenance.check_service_plans()  # as beat runs it
    assert work.status == WorkOrder.Status.DUE
    floor.LATE_CHECK_SECONDS = 0
    harness.step(1)
    harness.step(1)
    (alert,) = open_alerts(Source.MAINTENANCE)
    assert alert.vehicle.serial_number == "AGV-1"
    assert work.title in alert.message, alert.message

    maintenance.advance_work_order(work_order=work, status="IN_PROGRESS")
    harness.step(1)
    assert open_alerts(Source.MAINTENANCE) == []
