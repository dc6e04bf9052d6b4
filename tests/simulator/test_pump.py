"""The many-vehicle pump (`simulator.pump`) against the real Mosquitto: every vehicle's periodic
state and visualization leave at their rates, and a vehicle drives an order it is sent."""

from __future__ import annotations

import json
import threading
import time
from collections import Counter
from collections.abc import Iterator
from pathlib import Path

import pytest

from simulator import FleetConfig
from simulator.pump import PumpFleet, build_pump
from tests.simulator.builders import LAYOUT_DICT, make_order
from tests.simulator.recorder import Recorder, needs_broker
from vda5050 import encode

pytestmark = needs_broker

VEHICLES = 40


@pytest.fixture
def pump(recorder: Recorder, tmp_path: Path) -> Iterator[PumpFleet]:
    layout = tmp_path / "layout.json"
    layout.write_text(json.dumps(LAYOUT_DICT))
    config = FleetConfig(
        count=VEHICLES,
        interface=recorder.interface,
        state_interval=0.5,
        visualization_hz=2.0,
        time_scale=10.0,
    )
    fleet = build_pump(config, str(layout), slices=10)
    stop = threading.Event()
    thread = threading.Thread(target=fleet.run, args=(stop,), daemon=True)
    recorder.subscribe()
    thread.start()
    yield fleet
    stop.set()
    thread.join(timeout=10.0)
    assert not thread.is_alive()


def test_every_vehicle_publishes_at_its_rates(pump: PumpFleet, recorder: Recorder) -> None:
    recorder.wait_for(lambda m: m.kind == "state", timeout=10.0)
    time.sleep(1.0)  # connected and staggered
    start = time.monotonic()
    time.sleep(3.0)
    end = time.monotonic()
    window = [m for m in list(recorder.messages) if start <= m.at < end]
    states = Counter(m.serial for m in window if m.kind == "state")
    pictures = Counter(m.serial for m in window if m.kind == "visualization")
    serials = {f"AGV-{i + 1}" for i in range(VEHICLES)}
    assert set(states) == serials
    assert set(pictures) == serials
    # 3 s at a state every 0.5 s and visualization at 2 Hz: 6 each (±1 for the window's edges);
    # a vehicle skipped by the tick loop would show up as fewer.
    assert all(5 <= n <= 7 for n in states.values()), states
    assert all(5 <= n <= 7 for n in pictures.values()), pictures
    # ... and each as it is due: a write held back to a later sweep would show as states arriving
    # in pairs a second apart.
    arrivals: dict[str, list[float]] = {}
    for m in window:
        if m.kind == "state":
            arrivals.setdefault(m.serial, []).append(m.at)
    gaps = [b - a for times in arrivals.values() for a, b in zip(times, times[1:], strict=False)]
    assert max(gaps) < 0.9, max(gaps)


def test_a_vehicle_of_the_pump_drives_its_order(pump: PumpFleet, recorder: Recorder) -> None:
    recorder.wait_for(lambda m: m.kind == "state" and m.serial == "AGV-7", timeout=10.0)
    order = make_order("o-pump", ["n1", "n2", "n3"], serial="AGV-7")
    recorder.publish("AGV-7", "order", encode(order))
    done = recorder.wait_for(
        lambda m: (
            m.kind == "state"
            and m.serial == "AGV-7"
            and m.data["orderId"] == "o-pump"
            and m.data["lastNodeId"] == "n3"
            and not m.data["nodeStates"]
        ),
        timeout=20.0,
    )
    assert done.data["driving"] is False
