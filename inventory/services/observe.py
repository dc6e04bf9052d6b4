"""Compare the loads vehicles report (`state.loads`) with the inventory, after each flush.

A vehicle reporting a load the inventory does not place on it opens UNEXPECTED_LOAD and moves
the load onto the vehicle (the vehicle is the better witness: a load on a vehicle is at that
vehicle); it clears when the vehicle no longer reports it. A load the inventory places on a
vehicle that the vehicle does not report opens MISSING_LOAD (PICK_EMPTY right after a pick);
it clears when the vehicle reports it again or staff put the load elsewhere. A mismatch counts
only after it persisted for the grace time (`conf.discrepancy_grace_seconds`). A state that
omits `loads` (unknown, REFERENCE F.32; `[]` is unloaded) is left out.
"""

import logging
import time
from collections import defaultdict
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

from django.db import transaction

from inventory import conf
from inventory.models import Discrepancy, LoadCarrier, Movement
from inventory.services.stock import _open, _place, close_discrepancies

logger = logging.getLogger(__name__)

ANONYMOUS = "?"  # a reported load without loadId


@dataclass
class LoadObserver:
    """Holds the first-seen time of each unconfirmed mismatch between flushes."""

    clock: Callable[[], float] = time.monotonic
    pending: dict[str, float] = field(default_factory=dict)
    # (vehicle, load) pairs the vehicle has reported since it got the load: a load missing
    # after that was lost, one never reported after its pick was never picked.
    confirmed: dict[int, set[str]] = field(default_factory=dict)

    def observe(self, snapshots: Sequence[Mapping[str, Any]]) -> int:
        """Returns how many discrepancies this call opened."""
        # REFERENCE F.32: a state without `loads` says nothing about them (unknown, unlike []),
        # so it neither confirms nor contradicts the inventory.
        snaps = [
            s
            for s in snapshots
            if s.get("last_seen") is not None and s.get("loads_known", True) is not False
        ]
        if not snaps:
            return 0
        now, grace = self.clock(), conf.discrepancy_grace_seconds()
        pks = [int(s["pk"]) for s in snaps]
        expected: dict[int, dict[str, LoadCarrier]] = defaultdict(dict)
        # Loads on vehicles are few (at most a handful per vehicle): fetching all of them is
        # cheaper than an IN list of every flushed vehicle.
        wanted = set(pks)
        for load in LoadCarrier.objects.filter(vehicle__isnull=False):
            if load.vehicle_id in wanted:
                expected[load.vehicle_id][load.load_id] = load
        reported = {int(s["pk"]): _reported(s) for s in snaps}
        candidates: dict[str, tuple[str, int, str]] = {}
        for pk in pks:
            mine, theirs = set(expected[pk]), reported[pk]
            self.confirmed[pk] = (self.confirmed.get(pk, set()) & mine) | (mine & theirs)
            anonymous = ANONYMOUS in theirs
            for load_id in theirs - mine - {ANONYMOUS}:
                candidates[f"inv:unexpected:{pk}:{load_id}"] = ("unexpected", pk, load_id)
            if anonymous and not mine:
                candidates[f"inv:unexpected:{pk}:{ANONYMOUS}"] = ("unexpected", pk, ANONYMOUS)
            missing = mine - theirs
            if anonymous and missing:
                # A vehicle that cannot read load ids vouches for one expected load.
                missing = set(sorted(missing)[1:])
            for load_id in missing:
                candidates[f"inv:missing:{pk}:{load_id}"] = ("missing", pk, load_id)
        for key in [k for k in self.pending if _vehicle_of(k) in wanted and k not in candidates]:
            del self.pending[key]
        opened = 0
        with transaction.atomic():
            self._clear(pks, reported, expected)
            for key, (kind, pk, load_id) in candidates.items():
                first = self.pending.setdefault(key, now)
                if now - first < grace:
                    continue
                opened += self._confirm(key, kind, pk, load_id, expected[pk].get(load_id))
        return opened

    def _confirm(self, key: str, kind: str, pk: int, load_id: str, load: LoadCarrier | None) -> int:
        exists = Discrepancy.objects.filter(key=key, resolved_at__isnull=True).exists()
        if kind == "unexpected":
            if load_id != ANONYMOUS:
                carrier = LoadCarrier.objects.select_for_update().filter(load_id=load_id).first()
                where = carrier.place if carrier else "not in the inventory"
                if carrier is None:
                    carrier = LoadCarrier.objects.create(load_id=load_id)
                _place(carrier, reason=Movement.Reason.STATE, vehicle_id=pk)
            else:
                where = "no load expected"
            if not exists:
                _open(
                    key,
                    kind=Discrepancy.Kind.UNEXPECTED_LOAD,
                    load_id="" if load_id == ANONYMOUS else load_id,
                    vehicle_id=pk,
                    message=f"vehicle {pk} carries {load_id} the inventory does not expect "
                    f"({where})",
                )
            return 0 if exists else 1
        if exists:
            return 0
        last = Movement.objects.filter(load__load_id=load_id).first()
        after_pick = (
            last is not None
            and last.reason == Movement.Reason.PICK
            and load_id not in self.confirmed.get(pk, set())
        )
        _open(
            key,
            kind=Discrepancy.Kind.PICK_EMPTY if after_pick else Discrepancy.Kind.MISSING_LOAD,
            load_id=load_id,
            vehicle_id=pk,
            order_ref=last.order_ref if last is not None else "",
            message=(
                f"pick of {load_id} found nothing: vehicle {pk} reports no load"
                if after_pick
                else f"vehicle {pk} should carry {load_id} but reports no such load"
            ),
        )
        return 1

    def _clear(
        self,
        pks: list[int],
        reported: dict[int, set[str]],
        expected: dict[int, dict[str, LoadCarrier]],
    ) -> None:
        """Close the open state discrepancies of these vehicles whose cause has gone."""
        cleared = []
        wanted = set(pks)
        for key, pk in Discrepancy.objects.filter(
            resolved_at__isnull=True, key__startswith="inv:", vehicle__isnull=False
        ).values_list("key", "vehicle_id"):
            if pk not in wanted:
                continue
            parts = key.split(":", 3)
            if len(parts) != 4 or parts[1] not in ("unexpected", "missing"):
                continue
            load_id = parts[3]
            gone = (
                load_id not in reported[pk]
                if parts[1] == "unexpected"
                else (load_id in reported[pk] or load_id not in expected[pk])
            )
            if gone:
                cleared.append(key)
        close_discrepancies(cleared)
        # A load the inventory only knew from a vehicle's report left that vehicle unobserved:
        # follow the report (its place is now unknown) instead of calling it missing.
        for key in cleared:
            _, kind, pk_text, load_id = key.split(":", 3)
            load = expected[int(pk_text)].pop(load_id, None)
            if kind == "unexpected" and load is not None:
                _place(load, reason=Movement.Reason.STATE)


def _reported(snapshot: Mapping[str, Any]) -> set[str]:
    loads = snapshot.get("loads") or []
    return {str(load.get("loadId") or ANONYMOUS) for load in loads if isinstance(load, dict)}


def _vehicle_of(key: str) -> int | None:
    parts = key.split(":")
    return int(parts[2]) if len(parts) >= 3 and parts[2].isdigit() else None


_observer = LoadObserver()


def observe_loads(*, snapshots: Sequence[Mapping[str, Any]]) -> int:
    """Check the flushed vehicles' reported loads against the inventory. Never raises."""
    try:
        return _observer.observe(snapshots)
    except Exception:
        logger.exception("inventory check of state.loads failed; retried with the next flush")
        return 0
