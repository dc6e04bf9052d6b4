"""Wires a ControlLoop from the settings: broker, store, command queue and broadcasts."""

from typing import Any

from django.conf import settings

from control import snapshots
from control.controller import Controller
from control.metrics import CauseLog, ControlMetrics, start_snapshots
from control.observer import SnapshotObserver
from control.persistence import DjangoStore, observe_floor
from control.runner import ControlLoop, MqttLink
from control.session import PROBE_AFTER
from fleet.control_queue import receive_commands
from fleet.mqtt import make_client
from fleet.realtime import LIVE_GROUP, broadcast, broadcast_json, vehicle_group


def build_control_loop() -> ControlLoop:
    """The control loop for the configured broker and interface (not yet running)."""
    # Alerts, inventory, battery and maintenance watch the flushed snapshots on their own
    # thread, so an alert flood never holds up order sync and publishing (issue 11).
    observer = SnapshotObserver(
        observe_floor, min_interval=settings.FLEET_CONTROL.get("OBSERVE_INTERVAL", 0.0)
    )
    controller = Controller(
        store=DjangoStore(observer=observer),
        interface_name=settings.VDA5050_INTERFACE,
        base_ahead=settings.FLEET_CONTROL["BASE_AHEAD"] or None,
        horizon=max(settings.FLEET_CONTROL.get("HORIZON_NODES", 0), 0) or None,
        traffic=settings.FLEET_CONTROL["TRAFFIC"],
        park_idle=settings.FLEET_CONTROL.get("TRAFFIC_PARK_IDLE", True),
        park_after=settings.FLEET_CONTROL.get("TRAFFIC_PARK_AFTER", 0.0),
        liveness_probe_after=settings.FLEET_CONTROL.get("LIVENESS_PROBE_AFTER", PROBE_AFTER),
        motion_flush_interval=settings.FLEET_CONTROL.get("MOTION_FLUSH_INTERVAL", 0.0),
    )
    client, address = make_client(
        settings.MQTT_URL,
        client_id_prefix="fleet-control",
        read_pause=settings.FLEET_CONTROL.get("MQTT_READ_PAUSE", 0.0),
    )
    link = MqttLink(client, address.host, address.port, controller)
    metrics = ControlMetrics(controller)  # counted in memory, snapshots to Redis for /metrics
    metrics.instrument(
        link, CauseLog(settings.CONTROL_CAUSE_LOG) if settings.CONTROL_CAUSE_LOG else None
    )
    loop = ControlLoop(
        controller,
        link,
        receive_commands=receive_commands,
        broadcast=_broadcast_vehicles,
        intervals=settings.FLEET_CONTROL,
        stream_vehicle=_stream_vehicle,
    )
    # One writer per term of leadership: a process that stepped down stops writing its figures.
    start_snapshots(metrics, settings.REDIS_URL, until=loop.finished)
    metrics.watch_pauses(until=loop.finished)
    observer.start(until=loop.finished)
    return loop


# What the live pages were last sent per vehicle: they get only the changes (snapshots.LiveDeltas).
_live_deltas = snapshots.LiveDeltas()


def _broadcast_vehicles(rows: list[dict[str, Any]]) -> None:
    """control's throttled live snapshot: what changed per vehicle, encoded once for all pages."""
    broadcast_json(LIVE_GROUP, "vehicles.update", _live_deltas.payload(rows))


def _stream_vehicle(pk: int, event: dict[str, Any]) -> None:
    broadcast(vehicle_group(pk), "vehicle.messages", event)
