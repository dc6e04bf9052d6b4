"""The periodic half of the controller: flushes to the database, browser broadcasts, the
vehicle page's message streams and the liveness probe. Runs on control's main loop; every
method takes the controller's lock in short holds (per 100 vehicles), so that state messages on
the paho thread never wait long behind it."""

import logging
import threading
import time
from collections.abc import Callable
from typing import Any

from control import broadcasts, snapshots
from control.capabilities import refuse_instant_action
from control.driver import OrderDriver
from control.execution import LayoutIndex
from control.live import Fleet, InstantActionTrack, LiveVehicle
from control.message_log import MessageLog
from control.ports import FlushBatch, Store
from control.publisher import ProtocolLimitError, Publisher
from control.traffic_link import TrafficLink
from control.wait_log import WaitLog

logger = logging.getLogger(__name__)

LOCK_CHUNK = 25  # vehicles per lock hold in the periodic collections (a few ms each)


class PeriodicWork:
    """Mixed into `control.controller.Controller` (which sets these attributes)."""

    store: Store
    fleet: Fleet
    lock: threading.RLock
    layouts: dict[str, LayoutIndex]
    messages: MessageLog
    publisher: Publisher
    driver: OrderDriver
    traffic: TrafficLink | None
    waits: WaitLog
    probe_after: float
    probe_grace: float
    motion_flush_interval: float
    counters: Any
    _unflushed_outcomes: list[InstantActionTrack]
    _job_requests: list[dict[str, Any]]
    # Whether a browser has the live page open (asked before each broadcast); a controller
    # whose rows someone reads without a page (a benchmark, a test) sets its own.
    live_page_open: Callable[[], bool] = broadcasts.LIVE_AUDIENCE.watching

    def collect_flush(self) -> FlushBatch:
        """Take what changed since the last flush (under the lock, without I/O).

        The vehicles go in chunks, each under the lock on its own: building 1,000 rows takes
        tens of milliseconds, and a state message waiting that long would delay the order
        update it causes."""
        batch = FlushBatch()
        with self.lock:
            batch.progress, self.driver.progress = self.driver.progress, []
            batch.command_outcomes, self._unflushed_outcomes = self._unflushed_outcomes, []
            batch.job_requests, self._job_requests = self._job_requests, []
            vehicles = list(self.fleet.vehicles.values())
        for start in range(0, len(vehicles), LOCK_CHUNK):
            with self.lock:
                now = time.monotonic()
                for vehicle in vehicles[start : start + LOCK_CHUNK]:
                    self._collect_vehicle(vehicle, batch, now)
        with self.lock:
            batch.traffic_waits = self.waits.take_finished()
        return batch

    def _collect_vehicle(self, vehicle: LiveVehicle, batch: FlushBatch, now: float) -> None:
        if vehicle.session.probe_due(now, self.probe_after):
            self._probe(vehicle, now)
        link = vehicle.session.link(now)
        if link is not vehicle.last_link:  # e.g. ONLINE -> UNREACHABLE on timeout
            vehicle.last_link = link
            vehicle.mark_changed()
        # Counted once the vehicle has a registry row: a new vehicle's first snapshot goes
        # with the next flush, and a dispatch asked for before it would find it not online.
        # The cheap tests first: a vehicle with an order is not idle, whatever else it is.
        available = vehicle.pk is not None and vehicle.is_idle and vehicle.is_available
        if available and not vehicle.was_available:
            batch.newly_available += 1
        vehicle.was_available = available
        if self.traffic is not None:
            self.waits.observe(vehicle, self.traffic.waiting_for(vehicle))
        batch.command_outcomes += vehicle.command_outcomes
        vehicle.command_outcomes = []
        if not vehicle.needs_flush:
            return
        if vehicle.pk is None:
            vehicle.needs_flush = False
            batch.new_vehicles.append(vehicle)
            return
        material = snapshots.material(vehicle)
        if (
            material == vehicle.flushed_material
            and now - vehicle.flushed_at < self.motion_flush_interval
            and not vehicle.factsheet_changed
        ):
            return  # only motion changed: written with a later flush (still marked)
        vehicle.needs_flush = False
        vehicle.flushed_material, vehicle.flushed_at = material, now
        batch.snapshots.append(snapshots.row(vehicle))
        if vehicle.factsheet_changed and vehicle.factsheet is not None:
            batch.factsheets[vehicle.pk] = vehicle.factsheet
            vehicle.factsheet_changed = False

    def _probe(self, vehicle: LiveVehicle, now: float) -> None:
        """Ask a silent vehicle for its state (control.session: liveness probe). Not when it
        may not take a stateRequest (factsheet, mode: E.25, I.39; its state timeout still
        applies) nor when we may not publish (standby): no answer would then mean nothing."""
        state = vehicle.state
        mode = str(state.operating_mode) if state is not None else None
        if not self.publisher.may_publish() or refuse_instant_action(
            vehicle.capabilities, mode, "stateRequest", {}
        ):
            return
        try:
            self.publisher.instant_action(vehicle, "stateRequest")
        except ProtocolLimitError:  # J.44, e.g. a topic too long for it: counted, not sent
            return
        vehicle.session.on_probe(now, self.probe_grace)
        self.counters["liveness_probes"] += 1

    def flush(self) -> None:
        """Write one batch; on a database error the batch is put back and retried next time."""
        batch = self.collect_flush()
        if not (
            batch.new_vehicles
            or batch.snapshots
            or batch.progress
            or batch.factsheets
            or batch.command_outcomes
            or batch.job_requests
            or batch.traffic_waits
        ):
            return
        try:
            registered = self.store.flush(batch)
        except Exception:
            logger.exception("flush failed; will retry")
            self._requeue(batch)
            return
        with self.lock:
            for vehicle in batch.new_vehicles:
                self.fleet.set_pk(vehicle, registered.get(vehicle.key))
                vehicle.needs_flush = True  # its snapshot goes with the next flush
        if batch.newly_available or batch.new_vehicles:
            self.store.request_dispatch()

    def _requeue(self, batch: FlushBatch) -> None:
        with self.lock:
            self.driver.progress[:0] = batch.progress
            self._unflushed_outcomes[:0] = batch.command_outcomes
            self._job_requests[:0] = batch.job_requests
            self.waits.finished[:0] = batch.traffic_waits
            unwritten = {snapshot["pk"] for snapshot in batch.snapshots}
            for vehicle in self.fleet.vehicles.values():
                if vehicle.pk is None or vehicle.pk in unwritten:
                    vehicle.needs_flush = True
                    vehicle.flushed_material = None  # not written: goes with the next flush
                if vehicle.pk in batch.factsheets:
                    vehicle.factsheet_changed = True

    def collect_broadcast(self) -> list[dict[str, Any]]:
        """Browser rows of the vehicles that changed since the last broadcast (in chunks under
        the lock, as in `collect_flush`); none while no browser has the live page open: the
        vehicles stay marked, so the first broadcast after a page opened has them all."""
        if not self.live_page_open():
            return []
        with self.lock:
            changed = [v for v in self.fleet.vehicles.values() if v.needs_broadcast]
        rows = []
        for start in range(0, len(changed), LOCK_CHUNK):
            with self.lock:
                for vehicle in changed[start : start + LOCK_CHUNK]:
                    vehicle.needs_broadcast = False
                    rows.append(snapshots.live_row(vehicle, self.layouts, self.traffic))
        return rows

    def watch_vehicle(self, command: dict[str, Any]) -> None:
        """Stream one vehicle's messages for a while (`vehicle.watch` from a vehicle page)."""
        with self.lock:
            vehicle = self.fleet.by_pk(command.get("vehicle", -1))
            if vehicle is None:
                return  # not connected since control started: the page shows the snapshot
            seconds = command.get("seconds")
            self.messages.watch(
                vehicle.key,
                seconds=float(seconds) if isinstance(seconds, int | float) else 30.0,
                full=bool(command.get("full")),
            )

    def collect_watched(self) -> list[tuple[int, dict[str, Any]]]:
        """Per watched vehicle (pk): its new raw messages and its browser row, to stream."""
        with self.lock:
            events = []
            for batch in self.messages.collect():
                vehicle = self.fleet.vehicles.get(batch.key)
                if vehicle is None or vehicle.pk is None:
                    continue
                payload: dict[str, Any] = {
                    "vehicle": snapshots.live_row(vehicle, self.layouts, self.traffic),
                    "messages": batch.messages,
                }
                if batch.latest is not None:
                    payload["latest"] = batch.latest
                events.append((vehicle.pk, payload))
            return events

    def all_browser_rows(self) -> list[dict[str, Any]]:
        with self.lock:
            return [
                snapshots.live_row(v, self.layouts, self.traffic)
                for v in self.fleet.vehicles.values()
            ]
