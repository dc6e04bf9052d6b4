"""Shared building blocks of the 2.x message Structs."""

from __future__ import annotations

from typing import Annotated, Any, TypeAlias

import msgspec

#: headerId is a uint32 (REFERENCE §2); enforced on decode, not on construction.
HeaderId: TypeAlias = Annotated[int, msgspec.Meta(ge=0, le=2**32 - 1)]

#: sequenceId / orderUpdateId must not be negative (schema ``minimum: 0``).
NonNegativeInt: TypeAlias = Annotated[int, msgspec.Meta(ge=0)]

#: ``actionParameters[].value``: the schema allows array, boolean, number, string, object
#: (but not null). int and float are both listed so integers survive a round trip unchanged.
ParameterValue: TypeAlias = bool | int | float | str | list[Any] | dict[str, Any]


class VDAStruct(msgspec.Struct, rename="camel", omit_defaults=True, gc=False):
    """Base of every VDA 5050 Struct.

    ``gc=False``: decoded messages are trees (no reference cycles), so the garbage collector
    need not track them; with 1,000 vehicles' states alive a full collection took 120-150 ms
    of control's main loop, and every state message added objects towards the next one.

    ``rename="camel"`` maps snake_case attributes to the camelCase wire names and
    ``omit_defaults=True`` drops optional fields left at ``None``, which is what keeps a
    message built without 2.1-only fields valid against the 2.0.0 schema. Subclasses also
    pass ``kw_only=True`` because msgspec does not inherit that option.
    """


class BoundingBoxReference(VDAStruct, kw_only=True):
    """Reference point of a load bounding box, in vehicle coordinates (state, factsheet)."""

    x: float
    y: float
    z: float
    theta: float | None = None


class LoadDimensions(VDAStruct, kw_only=True):
    """Dimensions of a load bounding box in metres (state, factsheet)."""

    length: float
    width: float
    height: float | None = None
