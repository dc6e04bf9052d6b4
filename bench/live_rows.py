"""The live page's vehicle rows inside `control`, in process: µs per row and rows per second.

control builds a browser row for every vehicle that changed since its last broadcast, 5 times a
second (`Controller.collect_broadcast`). Compares, in one run and on the same vehicles:

- before: every row built from scratch (`control.snapshots.browser_row`);
- after: rows that rebuild only what changed (`control.snapshots.live_row`): the route only when
  the node states changed, the footprint only with a new factsheet, the state's fields only
  with a new state (a visualization message brings only a pose);
- no page open: `collect_broadcast` when no browser watches the live page (nothing is built).

1,000 vehicles on a 50 × 40 aisle warehouse with traffic management on (every vehicle placed,
one in five with a planned route, so rows carry reservations). Three kinds of broadcast:
`moving` (a new state per vehicle, 0.5 m further; the node states change every 6th state),
`idle` (a new state saying the same) and `visualization` (a new pose only). Every row of the
incremental builder is checked against the one built from scratch: they must be equal.

    .venv/bin/python -m bench.live_rows [--quick] [--vehicles 1000] [--ticks 20] [--save]
"""

import argparse
import statistics
import time
from collections.abc import Callable
from datetime import UTC, datetime
from typing import Any

import vda5050
from bench import results
from bench.traffic_control import Store, layout_index
from control import snapshots
from control.controller import Controller
from control.live import LiveVehicle
from maps.demo import warehouse_layout
from vda5050.enums import ConnectionState

COLUMNS, ROWS = 50, 40  # aisle nodes 3 m apart (maps.demo)
SPACING = 3.0
STEP = 0.5  # metres per state: 1 m/s at 2 states a second (issue 11's load)
AHEAD = 6  # node states ahead of a driving vehicle, the first two released
FACTSHEET = {
    "physicalParameters": {"length": 1.3, "width": 0.9, "speedMax": 1.5},
    "agvGeometry": {"envelopes2d": [{"set": "body", "polygonPoints": [{"x": 0.8, "y": 0.5}]}]},
}


class Fleet:
    """The vehicles' lanes and states, and the Controller whose live model they fill."""

    def __init__(self, vehicles: int) -> None:
        layout, _ = layout_index(warehouse_layout(columns=COLUMNS, rows=ROWS, map_id="bench"))
        self.serials = [f"AGV-{i:04d}" for i in range(vehicles)]
        # Each vehicle has its own node on an even aisle row; the odd rows stay free for plans.
        self.homes = [(i % COLUMNS, 2 * (i // COLUMNS) % ROWS) for i in range(vehicles)]
        self.controller = Controller(
            store=Store(layout, self.serials), interface_name="uagv", traffic=True
        )
        self.controller.load()
        self.header = 0
        for serial, (column, row) in zip(self.serials, self.homes, strict=True):
            self._send(serial, "connection", self._connection(serial))
            state = self._state(serial, column, row, 0.0, driving=False)  # idle: traffic places it
            self._send(serial, "state", vda5050.encode(state))
        self.vehicles = [self.controller.fleet.vehicles[("sim", s)] for s in self.serials]
        self._plan_every_fifth()
        for vehicle in self.vehicles:
            vehicle.factsheet = dict(FACTSHEET)

    def _send(self, serial: str, topic: str, payload: bytes) -> None:
        self.controller.handle_message(f"uagv/v2/sim/{serial}/{topic}", payload)

    def _connection(self, serial: str) -> bytes:
        return vda5050.encode(
            vda5050.Connection(
                header_id=0,
                timestamp=vda5050.now_timestamp("2.0.0"),
                version="2.0.0",
                manufacturer="sim",
                serial_number=serial,
                connection_state=ConnectionState.ONLINE,
            )
        )

    def _plan_every_fifth(self) -> None:
        traffic = self.controller.traffic
        assert traffic is not None
        now = time.monotonic()
        for vehicle, (column, row) in list(zip(self.vehicles, self.homes, strict=True))[::5]:
            goal = f"A{min(column + 8, COLUMNS - 1)}.{row + 1}"  # overlapping the next one's
            traffic.start(vehicle, f"o-{vehicle.serial_number}", "bench", [goal], now)

    def _state(
        self, serial: str, column: int, row: int, travelled: float, *, driving: bool = True
    ) -> vda5050.State:
        """The vehicle `travelled` metres along its aisle row from its home node."""
        self.header += 1
        passed = int(travelled // SPACING)
        ahead = [f"A{(column + passed + k) % COLUMNS}.{row}" for k in range(1, AHEAD + 1)]
        return vda5050.State(
            header_id=self.header,
            timestamp="2026-11-22T08:00:00.00Z",
            version="2.0.0",
            manufacturer="sim",
            serial_number=serial,
            order_id=f"o-{serial}" if driving else "",
            order_update_id=0,
            last_node_id=f"A{(column + passed) % COLUMNS}.{row}",
            last_node_sequence_id=2 * passed,
            driving=driving,
            operating_mode=vda5050.OperatingMode.AUTOMATIC,
            node_states=[
                vda5050.NodeState(node_id=n, sequence_id=2 * (passed + k) + 2, released=k < 2)
                for k, n in enumerate(ahead if driving else [])
            ],
            edge_states=[],
            action_states=[],
            battery_state=vda5050.BatteryState(
                battery_charge=80.0 - travelled / 100, charging=False
            ),
            errors=[],
            safety_state=vda5050.SafetyState(e_stop=vda5050.EStop.NONE, field_violation=False),
            agv_position=vda5050.AgvPosition(
                x=(column * SPACING + travelled) % (COLUMNS * SPACING),
                y=row * SPACING,
                theta=0.0,
                map_id="bench",
                position_initialized=True,
            ),
        )

    def tick(self, kind: str, n: int) -> None:
        """Give every vehicle what broadcast `n` of `kind` brings (not timed)."""
        received = datetime.now(UTC)
        for vehicle, (column, row) in zip(self.vehicles, self.homes, strict=True):
            if kind == "visualization":
                position = vehicle.visual_position
                assert position is not None
                vehicle.visual_position = vda5050.AgvPosition(
                    x=position.x + STEP / 2,
                    y=position.y,
                    theta=0.0,
                    map_id="bench",
                    position_initialized=True,
                )
                continue
            travelled = n * STEP if kind == "moving" else 0.0
            state = self._state(
                vehicle.serial_number, column, row, travelled, driving=kind == "moving"
            )
            vehicle.apply_state(state, received_at=received)


def timed(build: Callable[[LiveVehicle], dict[str, Any]], vehicles: list[LiveVehicle]) -> float:
    """µs per row to build the rows of `vehicles`, in CPU time."""
    began = time.thread_time()
    for vehicle in vehicles:
        build(vehicle)
    return (time.thread_time() - began) / len(vehicles) * 1e6


def measure(vehicles: int, ticks: int) -> dict[str, Any]:
    fleet = Fleet(vehicles)
    controller = fleet.controller
    layouts, traffic = controller.layouts, controller.traffic

    def before(vehicle: LiveVehicle) -> dict[str, Any]:
        return snapshots.browser_row(vehicle, layouts, traffic)

    def after(vehicle: LiveVehicle) -> dict[str, Any]:
        return snapshots.live_row(vehicle, layouts, traffic)

    for vehicle in fleet.vehicles:
        assert after(vehicle) == before(vehicle)  # warm: each vehicle's parts exist
    figures: dict[str, Any] = {"vehicles": vehicles, "ticks": ticks}
    reserved = sum(1 for v in fleet.vehicles if before(v)["reserved"])
    figures["rows_with_reservations"] = reserved
    for kind in ("moving", "idle", "visualization"):
        samples: dict[str, list[float]] = {"before": [], "after": []}
        for n in range(1, ticks + 1):
            fleet.tick(kind, n)
            # Alternate which goes first, so neither always meets the warmer caches.
            order = (("before", before), ("after", after))
            for name, build in order if n % 2 else order[::-1]:
                samples[name].append(timed(build, fleet.vehicles))
            for vehicle in fleet.vehicles:
                assert after(vehicle) == before(vehicle), vehicle.serial_number
        for name, values in samples.items():
            figures[f"{kind}_{name}_us_per_row"] = round(statistics.median(values), 2)
    controller.live_page_open = lambda: False
    for vehicle in fleet.vehicles:
        vehicle.needs_broadcast = True
    began = time.thread_time()
    rows = controller.collect_broadcast()
    figures["no_page_collect_ms"] = round((time.thread_time() - began) * 1e3, 3)
    assert rows == []
    return figures


def report(figures: dict[str, Any]) -> None:
    print(
        f"live rows: {figures['vehicles']} vehicles, {figures['ticks']} broadcasts per kind, "
        f"traffic on ({figures['rows_with_reservations']} rows with reservations), CPU time"
    )
    print(f"  {'broadcast':14s} {'before µs/row':>14s} {'after µs/row':>13s} {'rows/s after':>13s}")
    for kind in ("moving", "idle", "visualization"):
        was, now = figures[f"{kind}_before_us_per_row"], figures[f"{kind}_after_us_per_row"]
        print(
            f"  {kind:14s} {was:14.2f} {now:13.2f} {1e6 / now:13,.0f}"
            f"   ({was / now:.1f}× faster; before {1e6 / was:,.0f} rows/s)"
        )
    print(f"  no page open: collect_broadcast {figures['no_page_collect_ms']} ms (nothing built)")
    moving_ms = figures["moving_after_us_per_row"] * figures["vehicles"] / 1e3
    was_ms = figures["moving_before_us_per_row"] * figures["vehicles"] / 1e3
    print(
        f"  a broadcast of {figures['vehicles']} moving vehicles: {moving_ms:.1f} ms "
        f"(before {was_ms:.1f} ms); 5 a second: {moving_ms / 2:.1f} % of a core "
        f"(before {was_ms / 2:.1f} %)"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="5 broadcasts per kind")
    parser.add_argument("--vehicles", type=int, default=1000)
    parser.add_argument("--ticks", type=int, default=20, help="broadcasts per kind")
    parser.add_argument("--save", action="store_true", help="write bench/results/live_rows.json")
    args = parser.parse_args()
    figures = measure(args.vehicles, 5 if args.quick else args.ticks)
    report(figures)
    if args.save:
        print(f"  written to {results.write('live_rows', figures)}")


if __name__ == "__main__":
    main()
