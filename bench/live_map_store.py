"""The vehicles `bench.live_map` drives: state messages along the aisles, and a store that
reads the layout from the database but keeps vehicles in memory (no flush writes)."""

import itertools
import math
from typing import Any

import msgspec

import vda5050
from control.execution import LayoutIndex
from control.persistence import DjangoStore
from control.ports import ActiveOrder, FlushBatch

SPACING = 3.0  # metres between aisle nodes (maps.demo)
_pks = itertools.count(1)


class BenchStore:
    """`control.controller.Store` for the benchmark: layouts from the database, the rest a no-op."""

    def load_layouts(self) -> dict[str, LayoutIndex]:
        return DjangoStore().load_layouts()

    def load_vehicles(self) -> list[dict[str, Any]]:
        return []

    def active_orders(self) -> list[ActiveOrder]:
        return []

    def flush(self, batch: FlushBatch) -> dict[tuple[str, str], int]:
        return {v.key: next(_pks) for v in batch.new_vehicles}

    def vehicle_dialects(self) -> dict[int, str]:
        return {}

    def layouts_revision(self) -> object:
        return 0

    def request_dispatch(self) -> None:
        return None


def state_message(
    index: int, header_id: int, t: float, speed: float, columns: int, rows: int, timestamp: str
) -> tuple[str, bytes]:
    """Vehicle `index` at time `t`: even vehicles drive back and forth along a row, odd ones
    along a column, spread out; the next three aisle nodes ahead are its route (two released)."""
    along_row = index % 2 == 0
    # lane: which row or column; slot: the vehicle's place among those sharing that lane
    slot, lane = divmod(index // 2, rows if along_row else columns)
    nodes = columns if along_row else rows
    length = (nodes - 1) * SPACING
    per_lane = max(1, math.ceil(500 / (rows if along_row else columns)))
    travelled = (slot * 2 * length / per_lane + speed * t) % (2 * length)
    forward = travelled <= length
    offset = travelled if forward else 2 * length - travelled
    step = 1 if forward else -1
    at = int(offset // SPACING) if forward else math.ceil(offset / SPACING)
    ahead = [at + step * k for k in (1, 2, 3) if 0 <= at + step * k < nodes]
    lane_at = lane * SPACING
    if along_row:
        x, y, theta = offset, lane_at, 0.0 if forward else math.pi
        node_ids = [f"A{n}.{lane}" for n in ahead]
        last = f"A{at}.{lane}"
    else:
        x, y, theta = lane_at, offset, math.pi / 2 if forward else -math.pi / 2
        node_ids = [f"A{lane}.{n}" for n in ahead]
        last = f"A{lane}.{at}"
    serial = f"AGV-{index:04d}"
    message = vda5050.State(
        header_id=header_id,
        timestamp=timestamp,  # one per tick: formatting it costs as much as the rest
        version="2.0.0",
        manufacturer="bench",
        serial_number=serial,
        order_id=f"o-{index}",
        order_update_id=0,
        last_node_id=last,
        last_node_sequence_id=0,
        driving=True,
        operating_mode=vda5050.OperatingMode.AUTOMATIC,
        node_states=[
            vda5050.NodeState(node_id=n, sequence_id=2 + 2 * i, released=i < 2)
            for i, n in enumerate(node_ids)
        ],
        edge_states=[],
        action_states=[],
        battery_state=vda5050.BatteryState(battery_charge=50.0 + index % 50, charging=False),
        errors=[],
        loads=[vda5050.Load(load_id=f"L{index}", load_type="EPAL")] if index % 2 else [],
        safety_state=vda5050.SafetyState(e_stop=vda5050.EStop.NONE, field_violation=False),
        agv_position=vda5050.AgvPosition(
            x=x, y=y, theta=theta, map_id="bench", position_initialized=True
        ),
    )
    # msgspec directly: vda5050.encode's NaN scan costs more than control's handling of the
    # message, and these values are finite by construction.
    return f"uagv/v2/bench/{serial}/state", msgspec.json.encode(message)
