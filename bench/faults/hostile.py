"""Hostile VDA 5050 state payloads, every class of RELIABILITY.md §3 row 6, for one vehicle.

`generate(serial, count, rng)` yields (kind, payload) pairs: kind "reject" must be refused and
counted by `control`; "accept" is a valid state with unknown fields added (VDA JSON is
extensible: unknown fields are ignored and the state applies).
"""

import json
import random
from collections.abc import Iterator
from typing import Any

REJECT, ACCEPT = "reject", "accept"


def valid_state(serial: str, header_id: int, last_node: str = "a") -> dict[str, Any]:
    """A minimal valid 2.0.0 state of manufacturer `sim`."""
    return {
        "headerId": header_id,
        "timestamp": "2026-01-01T00:00:00.00Z",
        "version": "2.0.0",
        "manufacturer": "sim",
        "serialNumber": serial,
        "orderId": "",
        "orderUpdateId": 0,
        "lastNodeId": last_node,
        "lastNodeSequenceId": 0,
        "driving": False,
        "operatingMode": "AUTOMATIC",
        "nodeStates": [],
        "edgeStates": [],
        "actionStates": [],
        "batteryState": {"batteryCharge": 80.0, "charging": False},
        "errors": [],
        "safetyState": {"eStop": "NONE", "fieldViolation": False},
        "agvPosition": {
            "x": 0.0,
            "y": 0.0,
            "theta": 0.0,
            "mapId": "demo",
            "positionInitialized": True,
        },
    }


def _encode(document: Any) -> bytes:
    return json.dumps(document).encode()


WRONG_TYPES: list[Any] = ["seven", -1, 1.5, None, [], {}, True, "", "x" * 5000, 2**70]


def _mutations(serial: str, rng: random.Random) -> list[bytes]:
    """Structural mutations of a valid state: each one breaks the schema."""
    base = valid_state(serial, rng.randrange(1, 2**31))
    out: list[bytes] = []
    key = rng.choice(sorted(k for k in base if k != "agvPosition"))  # required ones
    out.append(_encode({k: v for k, v in base.items() if k != key}))  # missing required
    for field in ("headerId", "batteryState", "nodeStates", "driving", "agvPosition", "errors"):
        wrong = rng.choice(
            [w for w in WRONG_TYPES if type(w) not in (type(base[field]), type(None))]
        )
        out.append(_encode({**base, field: wrong}))  # wrong type
    nested = json.loads(json.dumps(base))
    nested["batteryState"]["batteryCharge"] = "full"
    out.append(_encode(nested))
    nested = json.loads(json.dumps(base))
    nested["nodeStates"] = [{"nodeId": rng.randrange(100)}]
    out.append(_encode(nested))
    nested = json.loads(json.dumps(base))
    nested["operatingMode"] = "TURBO"
    out.append(_encode(nested))
    text = _encode(base).decode()
    for token in ("NaN", "Infinity", "-Infinity", "1e400", "-1e400"):
        out.append(text.replace('"batteryCharge": 80.0', f'"batteryCharge": {token}').encode())
        out.append(text.replace('"x": 0.0', f'"x": {token}').encode())
    # Duplicate keys: the second headerId is a string (refused whichever one wins).
    out.append(text.replace('"headerId": ', '"headerId": "dup", "headerId": ', 1).encode())
    cut = rng.randrange(1, len(text) - 1)
    out.append(text[:cut].encode())  # truncated JSON
    out.append(text.encode("utf-16"))  # not UTF-8
    out.append(_encode(base)[:cut] + bytes([rng.randrange(0x80, 0x100)]) + _encode(base)[cut:])
    return out


def _fixed(serial: str) -> list[bytes]:
    depth = 5_000
    return [
        b"",
        b"{",
        b"null",
        b"[]",
        b"42",
        b'"state"',
        b"\xff\xfe\xfd",
        b"[" * depth + b"]" * depth,
        b'{"a":' * depth + b"1" + b"}" * depth,
        b'{"headerId": NaN}',
        b'{"headerId": Infinity}',
        b'{"headerId": 1e400}',
        _encode(valid_state(serial, 1))[:-1] + b"}}}}",
    ]


def oversized(serial: str, megabytes: float) -> bytes:
    """A syntactically valid state padded past the size limit (refused before parsing)."""
    document = valid_state(serial, 1)
    document["padding"] = "x" * int(megabytes * 1024 * 1024)
    return _encode(document)


def with_unknown_fields(serial: str, header_id: int, last_node: str) -> bytes:
    """Valid, plus vendor fields at the top, in nested objects and in list items."""
    document = valid_state(serial, header_id, last_node)
    document["vendorExtension"] = {"firmware": "1.2.3", "nested": [1, {"deep": True}]}
    document["batteryState"]["cellTemperatures"] = [21.5, 22.0]
    document["agvPosition"]["covariance"] = [0.1, 0.0, 0.1]
    document["errors"] = []
    document["information"] = [{"infoType": "x", "infoLevel": "INFO", "vendorNote": "hi"}]
    return _encode(document)


def generate(
    serial: str, count: int, rng: random.Random, *, big: tuple[float, ...] = (1.5, 10.0)
) -> Iterator[tuple[str, bytes]]:
    """`count` payloads: the fixed set and oversized ones once, then random mutations; one in
    50 is a valid state with unknown fields (header ids increasing, so each applies)."""
    sent = 0
    header_id = 1_000
    pending = [(REJECT, p) for p in _fixed(serial)] + [(REJECT, oversized(serial, m)) for m in big]
    while sent < count:
        if not pending:
            pending = [(REJECT, p) for p in _mutations(serial, rng)]
            rng.shuffle(pending)
        if sent % 50 == 49:
            header_id += 1
            yield ACCEPT, with_unknown_fields(serial, header_id, f"u{header_id}")
        else:
            yield pending.pop()
        sent += 1
