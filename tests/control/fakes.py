"""A fake store and vehicle-state builders for controller tests without MQTT or a database."""

from dataclasses import dataclass, field
from typing import Any

import vda5050
from control.execution import LayoutIndex, NodePlace
from control.ports import ActiveOrder, FlushBatch

# The protocol version the fake vehicle speaks; tests/control/conftest.py runs every controller
# test once per version.
PROTOCOL = {"version": "2.0.0"}

LINE = LayoutIndex(
    "demo",
    nodes={n: NodePlace(float(i), 0.0, None, "demo") for i, n in enumerate(["a", "b", "c", "d"])},
    edges={("a", "b"): "ab", ("b", "c"): "bc", ("c", "d"): "cd"},
)


@dataclass
class FakeStore:
    orders: list[ActiveOrder] = field(default_factory=list)
    batches: list[FlushBatch] = field(default_factory=list)
    dispatches: int = 0
    fail_flush: bool = False

    def load_layouts(self) -> dict[str, LayoutIndex]:
        return {"demo": LINE}

    def load_vehicles(self) -> list[dict[str, Any]]:
        return [
            {
                "pk": 1,
                "manufacturer": "sim",
                "serial_number": "AGV-1",
                "interface_name": "uagv",
                "protocol_version": PROTOCOL["version"],
            }
        ]

    def active_orders(self) -> list[ActiveOrder]:
        return self.orders

    def flush(self, batch: FlushBatch) -> dict[tuple[str, str], int]:
        if self.fail_flush:
            raise ConnectionError("database is down")
        self.batches.append(batch)
        return {v.key: 100 + i for i, v in enumerate(batch.new_vehicles)}

    def vehicle_dialects(self) -> dict[int, str]:
        return {}

    def layouts_revision(self) -> object:
        return 0

    def request_dispatch(self) -> None:
        self.dispatches += 1


def order(route: list[str] | None = None, **kwargs: Any) -> ActiveOrder:
    return ActiveOrder(
        transport_order_id=7,
        vda_order_id="TO-7",
        vehicle_pk=1,
        route=route or ["a", "b", "c", "d"],
        pickup_node="b",
        map_id="demo",
        pick_station="PICK-1",
        drop_station="DROP-1",
        **kwargs,
    )


def state(
    *,
    header_id: int = 1,
    order_id: str = "",
    last_node: str = "a",
    nodes: tuple[str, ...] = (),
    actions: tuple[tuple[str, str], ...] = (),
    errors: tuple[tuple[str, str, str], ...] = (),
    driving: bool = False,
    serial: str = "AGV-1",
    update_id: int = 0,
    horizon: tuple[str, ...] = (),
    mode: str = "AUTOMATIC",
    localized: bool = True,
) -> bytes:
    """An encoded 2.0.0 state on ROUTE a-b-c-d: `nodes` still to drive (released), `horizon`
    (unreleased), `actions` (id, status), `errors` (type, level, referenced orderId).
    Sequence ids are those of the route: 2·index for nodes, one less for the edge into it."""
    pending = [(n, True) for n in nodes] + [(n, False) for n in horizon]
    message = vda5050.State(
        header_id=header_id,
        timestamp="2026-01-01T00:00:00.00Z",
        version=PROTOCOL["version"],
        manufacturer="sim",
        serial_number=serial,
        order_id=order_id,
        order_update_id=update_id,
        last_node_id=last_node,
        last_node_sequence_id=_seq(last_node),
        driving=driving,
        operating_mode=vda5050.OperatingMode(mode),
        node_states=[
            vda5050.NodeState(node_id=n, sequence_id=_seq(n), released=r) for n, r in pending
        ],
        edge_states=[
            vda5050.EdgeState(edge_id=f"e{i}", sequence_id=_seq(n) - 1, released=r)
            for i, (n, r) in enumerate(pending)
        ],
        action_states=[
            vda5050.ActionState(action_id=a, action_status=vda5050.ActionStatus(s))
            for a, s in actions
        ],
        battery_state=vda5050.BatteryState(battery_charge=80.0, charging=False),
        errors=[
            vda5050.Error(
                error_type=t,
                error_level=vda5050.ErrorLevel(level),
                error_references=[
                    vda5050.ErrorReference(reference_key="orderId", reference_value=ref)
                ],
            )
            for t, level, ref in errors
        ],
        safety_state=vda5050.SafetyState(e_stop=vda5050.EStop.NONE, field_violation=False),
        agv_position=vda5050.AgvPosition(
            x=0.0, y=0.0, theta=0.0, map_id="demo", position_initialized=localized
        ),
    )
    if PROTOCOL["version"].startswith("3."):
        return vda5050.encode(vda5050.adapt.state_v2_to_v3(message))  # what a 3.0 robot sends
    return vda5050.encode(message)


def topic(serial: str = "AGV-1", kind: str = "state", manufacturer: str = "sim") -> str:
    """The topic of the fake vehicle's version."""
    major = vda5050.major_version_of(PROTOCOL["version"])
    return f"uagv/{major}/{manufacturer}/{serial}/{kind}"


ROUTE = ["a", "b", "c", "d"]


def _seq(node: str) -> int:
    return 2 * ROUTE.index(node) if node in ROUTE else 0
