"""What `control` distributes besides orders: map releases (2.1/3.0), zone sets and answers to
zone/edge requests (3.0). One facade the controller calls from its message handling, its sync
and its registry refresh; the logic is in `map_sync`, `zone_sets` and `requests`.
"""

from collections.abc import Callable
from typing import Any

from control.live import Fleet, InstantActionTrack, LiveVehicle, VehicleKey
from control.map_sync import MapStatus, MapSync, MapTarget
from control.ports import ActiveOrder
from control.publisher import Publisher
from control.requests import RequestArbiter
from control.zone_sets import ZoneSetSync
from vda5050 import v3
from vda5050.enums import TopicKind

SendAction = Callable[[LiveVehicle, str, dict[str, Any]], InstantActionTrack]


class Distribution:
    """Map sync, zone sets and request arbitration for the live fleet."""

    def __init__(self, publisher: Publisher, fleet: Fleet, send: SendAction) -> None:
        self.fleet = fleet
        self.maps = MapSync(send)
        self.zone_sets = ZoneSetSync(publisher.zone_set, send)
        self.requests = RequestArbiter(publisher.responses, fleet.vehicles.get)
        self._zone_seen: dict[tuple[VehicleKey, str], tuple[str, str]] = {}

    def after_message(self, vehicle: LiveVehicle, kind: str, raw: Any) -> None:
        """Follow up a message the controller applied (`raw` as decoded, 3.0 or 2.x)."""
        if kind == TopicKind.CONNECTION and str(raw.connection_state) == "ONLINE":
            self.zone_sets.forget(vehicle)
            self.requests.forget(vehicle)
        elif isinstance(raw, v3.Factsheet):
            self.zone_sets.on_factsheet(vehicle, raw)
        elif kind == TopicKind.STATE:
            self.maps.step(vehicle)
            if isinstance(raw, v3.State):
                self.zone_sets.on_state(vehicle, raw)
                self.requests.on_state(vehicle, raw)

    def set_targets(
        self, targets: dict[str, MapTarget], zone_sets: dict[str, v3.ZoneSetDefinition]
    ) -> None:
        """The released maps and the layouts' zone sets, from the database."""
        vehicles = list(self.fleet.vehicles.values())
        self.maps.set_targets(targets, vehicles)
        self.zone_sets.set_zone_sets(zone_sets, vehicles)

    def ready_orders(self, orders: list[ActiveOrder]) -> list[ActiveOrder]:
        """`orders` without the new ones whose vehicle lacks the order's map (K.47).

        Orders a vehicle already drives stay: holding them would stop their extension.
        """
        ready = []
        for order in orders:
            vehicle = self.fleet.by_pk(order.vehicle_pk)
            if vehicle is not None and vehicle.execution is None:
                reason = self.maps.order_refusal(vehicle, order.map_id)
                self.maps.note_hold(vehicle, order.map_id, reason)
                if reason is not None:
                    continue
            ready.append(order)
        return ready

    def tick(self) -> None:
        self.requests.tick()

    def collect_statuses(self) -> list[tuple[int, MapStatus, str, str]]:
        """(vehicle pk, map status, zoneSetId, zone-set status) of what changed since the last
        call; a vehicle not registered yet comes with a later call."""
        changed = self.maps.collect_keys()
        rows = []
        for key, status in self.maps.statuses.items():
            vehicle = self.fleet.vehicles.get(key[0])
            zone = self.zone_sets.status(vehicle, key[1]) if vehicle else ("", "")
            if self._zone_seen.get(key) != zone:
                self._zone_seen[key] = zone
                changed.add(key)
            if key not in changed:
                continue
            if vehicle is None or vehicle.pk is None:
                self.maps.changed.add(key)  # again once the flusher registered the vehicle
                continue
            rows.append((vehicle.pk, status, *zone))
        return rows

    def requeue(self, rows: list[tuple[int, MapStatus, str, str]]) -> None:
        """Statuses whose write failed: collect them again next time."""
        for pk, status, *_ in rows:
            vehicle = self.fleet.by_pk(pk)
            if vehicle is not None:
                self.maps.changed.add((vehicle.key, status.map_id))
