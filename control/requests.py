"""3.0 zone and edge requests answered on the `responses` topic (REFERENCE L.49).

The rule, deliberately simple: every request is for one resource, a zone (`zoneSetId`,
`zoneId`; ACCESS to a RELEASE zone and REPLANNING in a COORDINATED_REPLANNING zone alike) or a
corridor edge (`edgeId`). A resource is held by at most one vehicle. A request is GRANTED when no
other vehicle holds its resource, else QUEUED (first come, first served) and GRANTED as soon as
the holder lets go. A grant carries `leaseExpiry` = now + `LEASE`; while the holder keeps listing
the request we extend the lease by answering GRANTED again once less than half of it is left
(the vehicle reports states at least every 30 s). The holder lets go when its request is gone
from its state (it left the zone or finished the edge), reported EXPIRED or REVOKED, or when its
lease ran out without an extension (a vehicle that stopped reporting). We never revoke a grant
on our own, and nothing is REJECTED (unknown zones are arbitrated by their ids just the same).
An answer the vehicle has not taken up (still REQUESTED) is sent again after `RESEND_AFTER`
seconds: QoS 0 may lose it, and without an answer the vehicle waits.
"""

import time
from collections.abc import Callable
from dataclasses import dataclass, field
from datetime import UTC, datetime, timedelta

from control.live import LiveVehicle, VehicleKey
from vda5050 import v3
from vda5050.headers import format_timestamp

PublishResponses = Callable[[LiveVehicle, list[v3.Response]], None]
Resource = tuple[str, ...]


@dataclass
class _Grant:
    vehicle: VehicleKey
    request_id: str
    until: float  # monotonic


@dataclass
class _Answered:
    grant_type: str
    at: float


@dataclass
class RequestArbiter:
    """Grants zone and corridor requests, one vehicle per resource at a time."""

    publish: PublishResponses
    vehicles: Callable[[VehicleKey], LiveVehicle | None]
    LEASE: float = 120.0
    RESEND_AFTER: float = 5.0
    holders: dict[Resource, _Grant] = field(default_factory=dict)
    queues: dict[Resource, list[tuple[VehicleKey, str]]] = field(default_factory=dict)
    active: dict[VehicleKey, dict[str, Resource]] = field(default_factory=dict)
    answered: dict[tuple[VehicleKey, str], _Answered] = field(default_factory=dict)

    def on_state(self, vehicle: LiveVehicle, state: v3.State, now: float | None = None) -> None:
        """Answer the requests in this state; let go of what the vehicle no longer asks for."""
        key = vehicle.key
        if not (state.zone_requests or state.edge_requests or self.active.get(key)):
            return  # the usual state: nothing asked, nothing held (hot path)
        now = time.monotonic() if now is None else now
        listed: dict[str, tuple[Resource, str]] = {}
        for zone in state.zone_requests or []:
            resource: Resource = ("zone", zone.zone_set_id, zone.zone_id)
            listed[zone.request_id] = (resource, str(zone.request_status))
        for edge in state.edge_requests or []:
            listed[edge.request_id] = (("edge", edge.edge_id), str(edge.request_status))
        for request_id in list(self.active.get(key, {})):
            entry = listed.get(request_id)
            if entry is None or entry[1] in {"EXPIRED", "REVOKED"}:
                self._release(key, request_id, now)
        answers: list[v3.Response] = []
        for request_id, (resource, status) in listed.items():
            if status in {"EXPIRED", "REVOKED"}:
                continue
            self.active.setdefault(key, {})[request_id] = resource
            answer = self._decide(key, request_id, resource, status, now)
            if answer is not None:
                answers.append(answer)
        if answers:
            self.publish(vehicle, answers)

    def tick(self, now: float | None = None) -> None:
        """Free the resources whose lease ran out (the holder went silent)."""
        now = time.monotonic() if now is None else now
        for grant in [g for g in self.holders.values() if g.until < now]:
            self._release(grant.vehicle, grant.request_id, now)

    def forget(self, vehicle: LiveVehicle) -> None:
        """The vehicle reconnected: answer its requests anew."""
        for answered in [k for k in self.answered if k[0] == vehicle.key]:
            del self.answered[answered]

    def _decide(
        self, key: VehicleKey, request_id: str, resource: Resource, status: str, now: float
    ) -> v3.Response | None:
        holder = self.holders.get(resource)
        previous = self.answered.get((key, request_id))
        if holder is None or (holder.vehicle, holder.request_id) == (key, request_id):
            if holder is None:
                queue = self.queues.get(resource, [])
                if queue and queue[0] != (key, request_id):
                    return self._queue(key, request_id, resource, status, previous, now)
                if queue:
                    queue.pop(0)
                holder = self.holders[resource] = _Grant(key, request_id, now + self.LEASE)
            extend = status == "GRANTED" and holder.until - now < self.LEASE / 2
            fresh = previous is None or previous.grant_type != "GRANTED"
            resend = (
                status != "GRANTED"
                and now - (previous.at if previous else -1e9) >= self.RESEND_AFTER
            )
            if not (fresh or extend or resend):
                return None
            holder.until = now + self.LEASE
            self.answered[(key, request_id)] = _Answered("GRANTED", now)
            expiry = datetime.now(UTC) + timedelta(seconds=self.LEASE)
            return v3.Response(
                request_id=request_id,
                grant_type=v3.GrantType.GRANTED,
                lease_expiry=format_timestamp(expiry, "3.0.0"),
            )
        return self._queue(key, request_id, resource, status, previous, now)

    def _queue(
        self,
        key: VehicleKey,
        request_id: str,
        resource: Resource,
        status: str,
        previous: _Answered | None,
        now: float,
    ) -> v3.Response | None:
        queue = self.queues.setdefault(resource, [])
        if (key, request_id) not in queue:
            queue.append((key, request_id))
        if (
            previous is not None
            and previous.grant_type == "QUEUED"
            and (status != "REQUESTED" or now - previous.at < self.RESEND_AFTER)
        ):
            return None
        self.answered[(key, request_id)] = _Answered("QUEUED", now)
        return v3.Response(request_id=request_id, grant_type=v3.GrantType.QUEUED)

    def _release(self, key: VehicleKey, request_id: str, now: float) -> None:
        resource = self.active.get(key, {}).pop(request_id, None)
        self.answered.pop((key, request_id), None)
        if resource is None:
            return
        queue = self.queues.get(resource, [])
        if (key, request_id) in queue:
            queue.remove((key, request_id))
        holder = self.holders.get(resource)
        if holder is None or (holder.vehicle, holder.request_id) != (key, request_id):
            return
        del self.holders[resource]
        while queue:  # grant the next waiting vehicle at once, without waiting for its state
            next_key, next_id = queue.pop(0)
            vehicle = self.vehicles(next_key)
            if vehicle is None:
                continue
            self.holders[resource] = _Grant(next_key, next_id, now + self.LEASE)
            self.answered[(next_key, next_id)] = _Answered("GRANTED", now)
            expiry = datetime.now(UTC) + timedelta(seconds=self.LEASE)
            self.publish(
                vehicle,
                [
                    v3.Response(
                        request_id=next_id,
                        grant_type=v3.GrantType.GRANTED,
                        lease_expiry=format_timestamp(expiry, "3.0.0"),
                    )
                ],
            )
            return
