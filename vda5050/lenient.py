"""Input tolerance for VDA 5050 1.1 (deprecated, REFERENCE §1).

1.1 vehicles send what 2.0 sends, except that enum values may be lower/camel case
(``warning``, ``automatic``, ``autoAck``, ``connectionBroken``), ``state.information`` is
called ``informations`` and there is no factsheet. :func:`normalise_v1` rewrites a parsed
1.1 document in place into the 2.x shape, so it can be converted into the 2.x Structs.
Known enum fields are upper-cased; every other value, in particular free-form action
parameter values, is left alone.
"""

from __future__ import annotations

from typing import Any

from vda5050.enums import TopicKind

__all__ = ["ENUM_KEYS", "normalise_v1"]

#: Wire names of the fields whose values are 2.x enums (upper-cased on 1.1 input).
ENUM_KEYS = frozenset(
    {
        "actionStatus",
        "blockingType",
        "connectionState",
        "corridorRefPoint",
        "eStop",
        "errorLevel",
        "infoLevel",
        "mapStatus",
        "operatingMode",
        "orientationType",
    }
)

# Free-form values that must not be rewritten (an action parameter may well hold a key
# named "blockingType").
_OPAQUE_KEYS = frozenset({"value", "data"})


def normalise_v1(kind: TopicKind, document: Any) -> Any:
    """Rewrite a parsed 1.1 message of topic ``kind`` into the 2.x shape, in place.

    Iterative on purpose: the document is untrusted and may be nested deeply.
    """
    is_state = kind is TopicKind.STATE and isinstance(document, dict)
    if is_state and "informations" in document and "information" not in document:
        document["information"] = document.pop("informations")
    stack: list[Any] = [document]
    while stack:
        value = stack.pop()
        if isinstance(value, dict):
            for key, item in value.items():
                if key in ENUM_KEYS and isinstance(item, str):
                    value[key] = item.upper()
                elif key not in _OPAQUE_KEYS and isinstance(item, dict | list):
                    stack.append(item)
        elif isinstance(value, list):
            stack.extend(item for item in value if isinstance(item, dict | list))
    return document
