"""The live broadcast's rows: compact (empty fields left out, zeros kept) and with a footprint."""

from datetime import UTC, datetime
from typing import Any

import vda5050
from control.execution import LayoutIndex, NodePlace
from control.live import LiveVehicle
from control.snapshots import LiveDeltas, browser_row, compact_row

LAYOUT = LayoutIndex(
    "m",
    {"a": NodePlace(0.0, 0.0, None, "m"), "b": NodePlace(3.0, 0.0, None, "m")},
    {("a", "b"): "a-b"},
)


def _vehicle(factsheet: dict[str, Any] | None = None) -> LiveVehicle:
    vehicle = LiveVehicle("Acme", "AGV-1", "uagv", pk=7)
    vehicle.factsheet = factsheet
    state = vda5050.State(
        header_id=1,
        timestamp="2026-11-22T08:00:00.00Z",
        version="2.0.0",
        manufacturer="Acme",
        serial_number="AGV-1",
        order_id="",
        order_update_id=0,
        last_node_id="a",
        last_node_sequence_id=0,
        driving=False,
        operating_mode=vda5050.OperatingMode.AUTOMATIC,
        node_states=[vda5050.NodeState(node_id="b", sequence_id=2, released=False)],
        edge_states=[],
        action_states=[],
        battery_state=vda5050.BatteryState(battery_charge=0.0, charging=False),
        errors=[],
        safety_state=vda5050.SafetyState(e_stop=vda5050.EStop.NONE, field_violation=False),
        agv_position=vda5050.AgvPosition(
            x=0.0, y=1.23456, theta=0.0, map_id="m", position_initialized=True
        ),
    )
    vehicle.apply_state(state, received_at=datetime(2026, 11, 22, 8, 0, 0, tzinfo=UTC))
    return vehicle


def test_compact_row_leaves_out_empty_fields_and_keeps_zeros() -> None:
    row = compact_row(browser_row(_vehicle(), {"m": LAYOUT}))
    assert (row["x"], row["theta"], row["battery"]) == (0.0, 0.0, 0.0)
    assert row["y"] == 1.235  # millimetres
    assert row["horizon"] == [[3.0, 0.0]]
    for empty in ("order", "errors", "base", "waiting_for", "reserved", "transport_order"):
        assert empty not in row, empty
    assert (row["serial"], row["id"]) == ("AGV-1", 7)


def test_the_footprint_comes_from_the_factsheet_or_the_planning_default() -> None:
    assert browser_row(_vehicle(), {"m": LAYOUT})["size"] == [1.2, 0.8]
    factsheet = {"physicalParameters": {"length": 2.0, "width": 1.1, "speedMax": 1.5}}
    assert browser_row(_vehicle(factsheet), {"m": LAYOUT})["size"] == [2.0, 1.1]


def test_live_deltas_send_whole_rows_first_then_only_what_changed() -> None:
    deltas = LiveDeltas(keyframe_every=3)
    first = {"id": 7, "manufacturer": "Acme", "serial": "AGV-1", "x": 1.0, "errors": ["E1"]}
    assert deltas.payload([first]) == {"vehicles": [compact_row(first)], "changes": []}

    moved = first | {"x": 2.0, "errors": []}
    # only the pose and the cleared errors (None: the page drops the field)
    assert deltas.payload([moved]) == {
        "vehicles": [],
        "changes": [{"id": 7, "x": 2.0, "errors": None}],
    }
    newcomer = {"id": 8, "manufacturer": "Acme", "serial": "AGV-2", "x": 0.0}
    assert deltas.payload([moved, newcomer]) == {"vehicles": [compact_row(newcomer)], "changes": []}
    # every third broadcast is a keyframe: whole rows again for a page that joined late
    assert deltas.payload([moved]) == {"vehicles": [compact_row(moved)], "changes": []}
