"""Large live events go out in parts a websocket server accepts (fleet.realtime)."""

import json
from typing import Any

from hypothesis import given, settings
from hypothesis import strategies as st

from fleet.realtime import MAX_EVENT_BYTES, encode_events

ROW = {"id": 1, "serial": "P1-1", "route": [[12.0, 34.5]] * 40, "reserved": [[1.0, 2.0]] * 30}


def test_a_keyframe_of_a_busy_fleet_is_split_under_the_limit_in_order() -> None:
    rows = [dict(ROW, id=i) for i in range(1_000)]
    payload: dict[str, list[Any]] = {"vehicles": rows, "changes": [{"id": 5}]}
    whole = encode_events("vehicles.update", payload, limit=10**9)
    assert len(whole) == 1
    assert len(whole[0]) > MAX_EVENT_BYTES  # over the budget as one event

    texts = encode_events("vehicles.update", payload)

    assert len(texts) >= 2
    assert all(len(t.encode()) <= MAX_EVENT_BYTES for t in texts)
    events = [json.loads(t) for t in texts]
    assert {e["event"] for e in events} == {"vehicles.update"}
    assert [r["id"] for e in events for r in e["payload"]["vehicles"]] == list(range(1_000))
    assert [c for e in events for c in e["payload"]["changes"]] == [{"id": 5}]


def test_a_small_event_stays_whole() -> None:
    assert len(encode_events("vehicles.update", {"vehicles": [ROW], "changes": []})) == 1


@settings(max_examples=60, deadline=None)
@given(
    sizes=st.lists(st.integers(0, 400), max_size=60),
    changes=st.integers(0, 80),
    limit=st.integers(200, 5_000),
)
def test_parts_keep_every_item_in_order_and_stay_under_the_limit(
    sizes: list[int], changes: int, limit: int
) -> None:
    rows = [{"id": i, "pad": "x" * size} for i, size in enumerate(sizes)]
    changed = [{"id": i} for i in range(changes)]
    texts = encode_events("e", {"vehicles": rows, "changes": changed}, limit)

    payloads = [json.loads(t)["payload"] for t in texts]
    assert [r for p in payloads for r in p["vehicles"]] == rows
    assert [c for p in payloads for c in p["changes"]] == changed
    for text, payload in zip(texts, payloads, strict=True):
        alone = max(len(payload["vehicles"]), len(payload["changes"])) <= 1
        assert len(text.encode()) <= limit or alone  # only a single item may exceed it
