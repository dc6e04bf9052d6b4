"""Set-based bulk updates: many rows in one statement, the rows as one JSON parameter.

Django's `bulk_update` builds a `CASE WHEN pk = … THEN …` per field and row: about 0.5 ms of
CPU per row, and seconds for a thousand rows of a dozen fields (the report sampler's hourly
rows took a worker child 2–3 s every 15 s, docs/LOAD.md). A `VALUES` list with a
placeholder per field and row is cheaper, but psycopg re-parses a query that long on every
call. Here the rows travel as one JSON document: the query text is short and constant, and
PostgreSQL turns the document into typed rows (`jsonb_to_recordset`).
"""

from collections.abc import Mapping, Sequence
from typing import Any, cast

import msgspec
from django.db import connection
from django.db.models import Field, Model


def update_rows(
    model: type[Model],
    rows: Sequence[Mapping[str, Any]],
    fields: Sequence[str],
    *,
    batch_size: int = 1000,
) -> int:
    """Write `fields` of each row (a mapping with `pk` and a value per field name) as
    `bulk_update` would; the number of rows updated. One `UPDATE … FROM jsonb_to_recordset`
    per batch on PostgreSQL, `bulk_update` elsewhere (SQLite in the embedded demo)."""
    if not rows:
        return 0
    if connection.vendor != "postgresql":
        instances = [model(pk=row["pk"], **{name: row[name] for name in fields}) for row in rows]
        return model._default_manager.bulk_update(instances, list(fields), batch_size=500)
    columns = [cast("Field[Any, Any]", model._meta.get_field(name)) for name in fields]
    quote = connection.ops.quote_name
    record = ", ".join(
        ["pk bigint", *(f"{quote(f.column)} {f.db_type(connection)}" for f in columns)]
    )
    assignments = ", ".join(f"{quote(f.column)} = v.{quote(f.column)}" for f in columns)
    table, pk = quote(model._meta.db_table), quote(model._meta.pk.column)
    query = (  # identifiers and types from the model, the rows one parameter
        f"UPDATE {table} AS t SET {assignments} "  # noqa: S608
        f"FROM jsonb_to_recordset(%s::jsonb) AS v({record}) WHERE t.{pk} = v.pk"
    )
    names = [(name, field.column) for name, field in zip(fields, columns, strict=True)]
    updated = 0
    with connection.cursor() as cursor:
        for start in range(0, len(rows), batch_size):
            batch = [
                {"pk": row["pk"], **{column: row[name] for name, column in names}}
                for row in rows[start : start + batch_size]
            ]
            cursor.execute(query, [msgspec.json.encode(batch).decode()])
            updated += cursor.rowcount
    return updated
