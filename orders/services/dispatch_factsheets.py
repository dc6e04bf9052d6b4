"""Vehicle factsheets for dispatch, decoded once per process and per change.

Dispatch reads parts of every idle vehicle's factsheet each cycle (series name, height, critical
charge level, load sets, node actions). A factsheet is ~7 KB of JSON, most of it the action
catalogue, and decoding a thousand of them took 300-900 ms of each cycle, while they change only
when a vehicle sends a new one. So the cycle loads vehicles without it and asks the database
for a fingerprint of each: only factsheets not seen with that fingerprint are fetched and
decoded. On PostgreSQL the fingerprint is the 64-bit hash of the jsonb value (~20 ms for a
thousand, a quarter of MD5 over its text); elsewhere (SQLite in the demo) MD5 of the text.
"""

import json
from typing import Any

from django.db import connection
from django.db.models import BigIntegerField, Func, TextField
from django.db.models.functions import MD5, Cast

from robots.models import Vehicle

Digest = int | str | None


class _JsonbHash(Func):
    function = "jsonb_hash_extended"
    template = "%(function)s(%(expressions)s, 0)"
    output_field = BigIntegerField()


# vehicle pk -> (fingerprint, decoded factsheet). Bounded by the fleet's size; per process
# (each worker builds its own on its first cycle). Dict updates are atomic under the GIL.
# Nothing may change a decoded factsheet in place: it is handed out again every cycle.
_decoded: dict[int, tuple[Digest, Any]] = {}
# Canonical JSON of a factsheet's part -> the one decoded copy vehicles share: vehicles of one
# type differ only in their serial number and header, so a thousand decoded factsheets (32 MB)
# keep about one type's parts (the action catalogue is ~5 KB of each).
_parts: dict[str, Any] = {}
_MAX_PARTS = 10_000  # old parts of replaced factsheets are dropped past this


def attach_factsheets(vehicles: list[Vehicle], digests: dict[int, Digest] | None = None) -> None:
    """Set `factsheet` on `vehicles` (loaded with it deferred) as stored now: one query for the
    fingerprints (none when `digests` has them: a read annotated with `factsheet_digest`), one more
    for the factsheets that are new or changed."""
    if not vehicles:
        return
    if digests is None:
        digests = dict(
            Vehicle.objects.filter(pk__in=[v.pk for v in vehicles])
            .annotate(digest=factsheet_digest())
            .order_by()
            .values_list("pk", "digest")
        )
    missing = (None, None)
    stale = [pk for pk, now in digests.items() if _decoded.get(pk, missing)[0] != now]
    if stale:
        # A factsheet saved between the two queries is stored under the older fingerprint and
        # so fetched again next cycle: never kept stale.
        for pk, factsheet in (
            Vehicle.objects.filter(pk__in=stale).order_by().values_list("pk", "factsheet")
        ):
            _decoded[pk] = (digests[pk], _shared(factsheet))
    for vehicle in vehicles:
        vehicle.factsheet = _decoded.get(vehicle.pk, missing)[1] if vehicle.pk in digests else None


def factsheet_digest() -> Func:
    """The fingerprint of a vehicle's factsheet that `attach_factsheets` compares, as an
    expression to annotate a read of vehicles with."""
    if connection.vendor == "postgresql":
        return _JsonbHash("factsheet")
    return MD5(Cast("factsheet", output_field=TextField()))


def _shared(factsheet: Any) -> Any:
    """`factsheet` with each part (object or array) replaced by an equal one already kept."""
    if not isinstance(factsheet, dict):
        return factsheet
    if len(_parts) > _MAX_PARTS:
        _parts.clear()
    shared = {}
    for key, part in factsheet.items():
        if isinstance(part, dict | list):
            part = _parts.setdefault(json.dumps(part, sort_keys=True), part)
        shared[key] = part
    return shared


def forget() -> None:
    """Drop the decoded factsheets (tests; the next cycle fetches them all)."""
    _decoded.clear()
    _parts.clear()
