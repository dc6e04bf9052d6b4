"""Reads of the inventory: where a load is, open discrepancies, occupancy."""

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
