"""Alerts derived from the vehicles' live snapshots, evaluated after each `control` flush.

Stateless causes (errors, connection, battery) are read straight from the snapshot. Two causes
need a memory of earlier snapshots: "no progress" (since when has a vehicle with an order not
moved) and protocol violations (did the counters grow). That memory lives in this process
(`control` is the only caller, and a restart only delays these two by one threshold).
"""

import logging
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

from alerts import conf
from alerts.models import Alert, Severity, Source
from alerts.services.core import sync_causes

logger = logging.getLogger(__name__)

# Every snapshot-derived cause is "<kind>:<vehicle pk>[:<detail>]".
SNAPSHOT_KINDS = ("vda", "connection", "state_timeout", "battery", "no_progress", "protocol")
_VDA_LEVELS = {
    "WARNING": Severity.WARNING,
    "URGENT": Severity.URGENT,
    "CRITICAL": Severity.CRITICAL,
    "FATAL": Severity.FATAL,
}


@dataclass
class _Seen:
    """What this process remembers about one vehicle between flushes."""

    signature: tuple[Any, ...] = ()
    since: float = 0.0
    violations: int | None = None
    violation_at: float | None = None


@dataclass
class SnapshotObserver:
    """Turns snapshots into the set of active causes per vehicle and syncs the alerts."""

    clock: Any = time.monotonic
    seen: dict[int, _Seen] = field(default_factory=dict)

    def observe(self, snapshots: Sequence[Mapping[str, Any]]) -> tuple[int, int]:
        if not snapshots:
            return 0, 0
        now = self.clock()
        pks = [int(s["pk"]) for s in snapshots]
        # Open alerts are few; fetching them all beats an IN list of every flushed vehicle.
        open_battery = set(
            Alert.objects.exclude(status=Alert.Status.RESOLVED)
            .filter(source=Source.BATTERY)
            .values_list("vehicle_id", flat=True)
        )
        active: dict[str, dict[str, Any]] = {}
        for snapshot in snapshots:
            active.update(self._causes(snapshot, now, int(snapshot["pk"]) in open_battery))
        return sync_causes(
            prefixes=[f"{kind}:" for kind in SNAPSHOT_KINDS],
            active=active,
            scope={f"{kind}:{pk}" for pk in pks for kind in SNAPSHOT_KINDS},
        )

    def _causes(
        self, snap: Mapping[str, Any], now: float, battery_open: bool
    ) -> dict[str, dict[str, Any]]:
        pk = int(snap["pk"])
        order_ref = str(snap.get("order_id") or "")
        causes: dict[str, dict[str, Any]] = {}

        def add(cause: str, source: str, severity: str, message: str, **details: Any) -> None:
            causes[cause] = {
                "source": source,
                "severity": severity,
                "message": message,
                "vehicle": pk,
                "order_ref": order_ref,
                "details": details,
            }

        for error in snap.get("errors") or []:
            level = str(error.get("errorLevel", "")).upper()
            kind = str(error.get("errorType") or "error")
            description = error.get("errorDescription") or kind
            add(
                f"vda:{pk}:{kind}"[:200],
                Source.VDA_ERROR,
                _VDA_LEVELS.get(level, Severity.WARNING),
                f"vehicle reports {level or 'an'} error {kind}: {description}",
                error=dict(error),
            )
        connection = snap.get("connection")
        if connection == "CONNECTIONBROKEN":
            add(
                f"connection:{pk}",
                Source.CONNECTION,
                Severity.URGENT,
                "connection broken (the broker sent the vehicle's last will)",
            )
        elif connection == "UNREACHABLE":
            add(
                f"state_timeout:{pk}",
                Source.STATE_TIMEOUT,
                Severity.URGENT,
                "no state within the vehicle's state interval",
            )
        charge = snap.get("battery_charge")
        if charge is not None and not snap.get("charging"):
            limit = conf.low_battery_percent()
            if battery_open:
                limit += conf.battery_hysteresis_percent()
            if charge < limit:
                critical = charge < conf.critical_battery_percent()
                add(
                    f"battery:{pk}",
                    Source.BATTERY,
                    Severity.CRITICAL if critical else Severity.WARNING,
                    f"battery at {charge:.0f} %",
                    charge=charge,
                )
        seen = self.seen.setdefault(pk, _Seen(since=now))
        self._progress(snap, seen, now, add, pk)
        self._protocol(snap, seen, now, add, pk)
        return causes

    def _progress(
        self, snap: Mapping[str, Any], seen: _Seen, now: float, add: Any, pk: int
    ) -> None:
        x, y = snap.get("x"), snap.get("y")
        signature = (
            snap.get("order_id"),
            snap.get("last_node_id"),
            snap.get("last_node_sequence_id"),
            None if x is None else round(x, 1),
            None if y is None else round(y, 1),
        )
        if signature != seen.signature:
            seen.signature, seen.since = signature, now
        stuck_for = now - seen.since
        if snap.get("order_id") and stuck_for >= conf.no_progress_seconds():
            add(
                f"no_progress:{pk}",
                Source.NO_PROGRESS,
                Severity.URGENT,
                f"no progress on order {snap.get('order_id')} for {stuck_for:.0f} s",
                node=snap.get("last_node_id"),
            )

    def _protocol(
        self, snap: Mapping[str, Any], seen: _Seen, now: float, add: Any, pk: int
    ) -> None:
        ignored = conf.protocol_ignored_counters()
        counters = snap.get("protocol_counters") or {}
        total = sum(int(v) for k, v in counters.items() if k not in ignored)
        if seen.violations is not None and total > seen.violations:
            seen.violation_at = now
        seen.violations = total
        if (
            seen.violation_at is not None
            and now - seen.violation_at < conf.protocol_quiet_seconds()
        ):
            add(
                f"protocol:{pk}",
                Source.PROTOCOL,
                Severity.WARNING,
                "protocol violations: "
                + ", ".join(f"{k} {v}" for k, v in sorted(counters.items()) if k not in ignored),
                counters=dict(counters),
            )


_observer = SnapshotObserver()


def observe_snapshots(*, snapshots: Sequence[Mapping[str, Any]]) -> tuple[int, int]:
    """Raise and auto-resolve the snapshot-derived alerts of the vehicles in this flush.

    Never raises: a failure here must not lose the flush it follows (it is logged, and the
    next flush retries the same evaluation).
    """
    try:
        return _observer.observe(snapshots)
    except Exception:
        logger.exception("alert evaluation failed; retried with the next flush")
        return 0, 0
