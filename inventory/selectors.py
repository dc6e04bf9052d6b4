"""Reads of the inventory: where a load is, open discrepancies, occupancy."""

from collections.abc import Iterable

from django.db.models import Count, QuerySet

from inventory.models import Discrepancy, LoadCarrier, StorageLocation


def find_load(load_id: str) -> LoadCarrier | None:
    return (
        LoadCarrier.objects.select_related("location__station__map", "vehicle")
        .filter(load_id=load_id)
        .first()
    )


def open_discrepancies() -> QuerySet[Discrepancy]:
    return Discrepancy.objects.filter(resolved_at__isnull=True).select_related("location__station")


def occupancy() -> QuerySet[StorageLocation]:
    return StorageLocation.objects.select_related("station").annotate(used=Count("loads"))


def load_weights(load_ids: Iterable[str]) -> dict[str, float]:
    """The known weights (kg) of these loads, by load id (one query)."""
    wanted = {load_id for load_id in load_ids if load_id}
    if not wanted:
        return {}
    rows = LoadCarrier.objects.filter(load_id__in=wanted, weight__isnull=False)
    return {
        load_id: float(weight)
        for load_id, weight in rows.values_list("load_id", "weight")
        if weight is not None
    }
