"""`fleet.bulk.update_rows`: one statement for many rows writes exactly what Django's
`bulk_update` writes (times, NULLs, JSON, text with quotes), only the named fields."""

from datetime import UTC, datetime
from typing import Any

import pytest
from django.db import connection

from fleet.bulk import update_rows
from reports.models import SamplerMark
from robots.models import Vehicle

pytestmark = pytest.mark.django_db

FIELDS = ["at", "x", "y", "map_id", "battery_charge", "error_types"]
EARLIER = datetime(2026, 11, 27, 1, 0, tzinfo=UTC)


def _marks(count: int) -> list[SamplerMark]:
    vehicles = Vehicle.objects.bulk_create(
        Vehicle(manufacturer="m", serial_number=f"S{i}", interface_name="uagv")
        for i in range(count)
    )
    return SamplerMark.objects.bulk_create(
        SamplerMark(vehicle=v, at=EARLIER, x=0.0, y=0.0, map_id="old") for v in vehicles
    )


def _stored() -> list[tuple[object, ...]]:
    return list(SamplerMark.objects.order_by("pk").values_list("pk", *FIELDS))


@pytest.mark.parametrize("batch_size", [1000, 2])
def test_update_rows_stores_what_bulk_update_stores(batch_size: int) -> None:
    marks = _marks(5)
    values: list[dict[str, Any]] = [
        {"at": datetime(2026, 11, 27, 2, 3, 4, 500000, tzinfo=UTC), "x": 1.5, "y": -2.25},
        {"at": EARLIER, "x": None, "y": None, "map_id": 'hall "1" ü→\\'},
        {"battery_charge": 0.1 + 0.2, "error_types": ["noRoute", "it's"]},
        {"error_types": []},
        {},
    ]
    for mark, changes in zip(marks, values, strict=True):
        for name, value in changes.items():
            setattr(mark, name, value)
    rows = [{"pk": m.pk} | {name: getattr(m, name) for name in FIELDS} for m in marks]

    assert update_rows(SamplerMark, rows, FIELDS, batch_size=batch_size) == 5
    ours = _stored()
    SamplerMark.objects.update(at=EARLIER, x=0.0, y=0.0, map_id="old", error_types=[])
    SamplerMark.objects.bulk_update(marks, FIELDS)
    assert ours == _stored()
    assert ours[1][4] == 'hall "1" ü→\\'
    assert ours[2][5] == 0.1 + 0.2


def test_only_the_named_fields_are_written() -> None:
    mark = _marks(1)[0]
    update_rows(SamplerMark, [{"pk": mark.pk, "map_id": "new"}], ["map_id"])
    mark.refresh_from_db()
    assert (mark.map_id, mark.at, mark.x) == ("new", EARLIER, 0.0)
    assert update_rows(SamplerMark, [], ["map_id"]) == 0


def test_on_postgresql_it_is_one_statement_per_batch(django_assert_num_queries: Any) -> None:
    if connection.vendor != "postgresql":
        pytest.skip("the set-based path is PostgreSQL's")
    marks = _marks(5)
    rows = [{"pk": m.pk, "x": float(i)} for i, m in enumerate(marks)]
    with django_assert_num_queries(3):
        update_rows(SamplerMark, rows, ["x"], batch_size=2)
    assert [x for _, x in SamplerMark.objects.order_by("pk").values_list("pk", "x")] == [
        0.0,
        1.0,
        2.0,
        3.0,
        4.0,
    ]
