"""Stock positions: where each load is, changed by pick, drop, state and staff."""

from typing import Any

from django.db import IntegrityError, transaction
from django.db.models import Count
from django.utils import timezone

from fleet.exceptions import InvalidRequestError
from inventory.models import Discrepancy, LoadCarrier, Movement, StorageLocation
from maps.models import Station


def define_location(*, station: Station, capacity: int = 1, note: str = "") -> StorageLocation:
    """Make `station` a storage location (or change its capacity)."""
    if capacity < 1:
        raise InvalidRequestError("capacity must be at least 1")
    location, _ = StorageLocation.objects.update_or_create(
        station=station, defaults={"capacity": capacity, "note": note}
    )
    return location


def register_load(*, load_id: str, load_type: str = "EPAL", **dimensions: Any) -> LoadCarrier:
    """Create a load carrier (or update its type and dimensions); it starts nowhere."""
    if not load_id.strip():
        raise InvalidRequestError("a load needs a loadId")
    load, _ = LoadCarrier.objects.update_or_create(
        load_id=load_id.strip(), defaults={"load_type": load_type, **dimensions}
    )
    return load


def location_of(station_id: int) -> StorageLocation | None:
    return StorageLocation.objects.filter(station_id=station_id).first()


def _free_slot(location: StorageLocation, exclude: int | None = None) -> int | None:
    loads = LoadCarrier.objects.filter(location=location, slot__isnull=False)
    if exclude is not None:
        loads = loads.exclude(pk=exclude)
    taken = set(loads.values_list("slot", flat=True))
    return next((s for s in range(1, location.capacity + 1) if s not in taken), None)


def _place(
    load: LoadCarrier,
    *,
    reason: str,
    location: StorageLocation | None = None,
    vehicle_id: int | None = None,
    slot: int | None = None,
    order_ref: str = "",
) -> Movement | None:
    """Move `load` to a location or a vehicle (or nowhere) and record the movement."""
    if load.location_id == (location.pk if location else None) and load.vehicle_id == vehicle_id:
        return None
    movement = Movement(
        load=load,
        reason=reason,
        from_location_id=load.location_id,
        from_vehicle_id=load.vehicle_id,
        to_location=location,
        to_vehicle_id=vehicle_id,
        order_ref=order_ref[:100],
    )
    previous_location = load.location_id
    load.location, load.vehicle_id, load.slot = location, vehicle_id, slot
    load.save(update_fields=["location", "vehicle", "slot", "updated_at"])
    movement.save()
    if previous_location is not None:
        _recheck_full(previous_location)
    return movement


def _open(key: str, **fields: Any) -> Discrepancy:
    """Record a discrepancy once per key (idempotent while it is open)."""
    existing = Discrepancy.objects.filter(key=key, resolved_at__isnull=True).first()
    if existing is not None:
        return existing
    try:
        with transaction.atomic():
            return Discrepancy.objects.create(key=key[:200], **fields)
    except IntegrityError:
        return Discrepancy.objects.get(key=key, resolved_at__isnull=True)


def close_discrepancies(keys: list[str]) -> int:
    if not keys:
        return 0
    return Discrepancy.objects.filter(key__in=keys, resolved_at__isnull=True).update(
        resolved_at=timezone.now()
    )


def _recheck_full(location_id: int) -> None:
    """A drop-full discrepancy clears once the location is back within capacity."""
    location = StorageLocation.objects.annotate(n=Count("loads")).get(pk=location_id)
    if location.n <= location.capacity:
        close_discrepancies([f"inv:drop_full:{location_id}"])


@transaction.atomic
def record_pick(
    *, vehicle_id: int, station_id: int, load_id: str = "", load_type: str = "", order_ref: str = ""
) -> LoadCarrier | None:
    """A vehicle finished a pick at a station: the load is now on the vehicle.

    A pick at a storage location that holds no such load (or, without a load id, nothing at
    all) opens a PICK_EMPTY discrepancy; the vehicle's next states tell whether it really
    carries something (see `observe_loads`).
    """
    location = location_of(station_id)
    load: LoadCarrier | None = None
    if load_id:
        load = LoadCarrier.objects.select_for_update().filter(load_id=load_id).first()
        if load is None:
            load = LoadCarrier.objects.create(load_id=load_id, load_type=load_type or "EPAL")
    elif location is not None:
        load = (
            LoadCarrier.objects.select_for_update()
            .filter(location=location)
            .order_by("slot")
            .first()
        )
    if location is not None and (load is None or load.location_id != location.pk):
        _open(
            f"inv:pick_empty:{station_id}:{order_ref or load_id}",
            kind=Discrepancy.Kind.PICK_EMPTY,
            load_id=load_id,
            vehicle_id=vehicle_id,
            location=location,
            order_ref=order_ref,
            message=f"pick at {location.station.station_id} found no {load_id or 'load'} "
            "in the inventory",
        )
    if load is not None:
        _place(load, reason=Movement.Reason.PICK, vehicle_id=vehicle_id, order_ref=order_ref)
    return load


@transaction.atomic
def record_drop(
    *, vehicle_id: int, station_id: int, load_id: str = "", order_ref: str = ""
) -> LoadCarrier | None:
    """A vehicle finished a drop at a station: its load is now there, in the lowest free slot.

    Dropping onto a full location opens a DROP_FULL discrepancy (the load is still recorded
    there, without a slot: it physically is there).
    """
    load = (
        LoadCarrier.objects.select_for_update().filter(load_id=load_id).first()
        if load_id
        else LoadCarrier.objects.select_for_update().filter(vehicle_id=vehicle_id).first()
    )
    location = location_of(station_id)
    if load is None:
        return None
    if location is None:
        # Not a storage location (a conveyor, a hand-over to people): the load leaves the
        # inventory's view.
        _place(load, reason=Movement.Reason.DROP, order_ref=order_ref)
        return load
    slot = _free_slot(location, exclude=load.pk)
    if slot is None:
        _open(
            f"inv:drop_full:{location.pk}",
            kind=Discrepancy.Kind.DROP_FULL,
            load_id=load.load_id,
            vehicle_id=vehicle_id,
            location=location,
            order_ref=order_ref,
            message=f"drop of {load.load_id} at {location.station.station_id}: location is full "
            f"({location.capacity})",
        )
    _place(load, reason=Movement.Reason.DROP, location=location, slot=slot, order_ref=order_ref)
    return load


@transaction.atomic
def move_load(
    *, load: LoadCarrier, location: StorageLocation | None, reason: str = Movement.Reason.MANUAL
) -> Movement | None:
    """Staff (or an import) put a load somewhere by hand; clears what it contradicts."""
    slot = _free_slot(location, exclude=load.pk) if location is not None else None
    if location is not None and slot is None:
        raise InvalidRequestError(f"{location.station.station_id} is full")
    return _place(load, reason=reason, location=location, slot=slot)
