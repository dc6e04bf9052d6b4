"""J.44: the string limits are checked on the encoded message, deep inside it too; the scans
of the text that spare most messages the walk never let a violation through."""

import json
from typing import Any

import msgspec
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st

from control.capabilities import StringLimits
from control.limits import ProtocolLimitError, _check_string, _strings, check_message


def test_a_long_id_deep_in_an_order_is_refused_with_its_key_and_value() -> None:
    order = {
        "orderId": "o1",
        "nodes": [
            {"nodeId": "n1", "actions": [{"actionId": "a1", "actionParameters": []}]},
            {
                "nodeId": "n2",
                "actions": [
                    {
                        "actionId": "a2",
                        "actionParameters": [{"key": "loadId", "value": "L" * 9}],
                    }
                ],
            },
        ],
    }
    payload = msgspec.json.encode(order)
    check_message(StringLimits(id_len=2, load_id_len=9), "uagv/v2/m/s/order", payload)
    with pytest.raises(ProtocolLimitError, match="loadId 'LLLLLLLLL' exceeds loadIdLen 8"):
        check_message(StringLimits(id_len=2, load_id_len=8), "uagv/v2/m/s/order", payload)
    with pytest.raises(ProtocolLimitError, match="orderId 'o1' is not numerical"):
        check_message(StringLimits(id_numerical_only=True), "uagv/v2/m/s/order", payload)


CHECKED = ["orderId", "nodeId", "edgeId", "actionId", "mapId", "loadId", "blockingType"]
CHECKED += ["orientationType", "corridorRefPoint"]
OTHER = ["actionType", "startNodeId", "nodeDescription", "x", "value", "key"]
texts = st.text(st.characters(exclude_categories=["Cs"]), max_size=14) | st.sampled_from(
    ["", "7", "12345", 'a"b', "back\\slash", '"nodeId":"x"', "äöü €", "١٢", "x" * 13]
    + ['a"' + "b" * 12, "\\" + "c" * 12, "\u00e4" * 3]  # escaped early, long after
)
parameters = st.fixed_dictionaries(
    {"key": st.sampled_from(CHECKED + OTHER), "value": texts | st.lists(texts, max_size=2)}
)
values = st.recursive(
    texts | st.integers() | st.none() | parameters,
    lambda children: (
        st.lists(children, max_size=3)
        | st.dictionaries(st.sampled_from(CHECKED + OTHER), children, max_size=4)
    ),
    max_leaves=20,
)
LOAD_8 = StringLimits(load_id_len=8)
limits = st.builds(
    StringLimits,
    id_len=st.none() | st.integers(0, 12),
    id_numerical_only=st.booleans(),
    enum_len=st.none() | st.integers(0, 12),
    load_id_len=st.none() | st.integers(0, 12),
)


def walked_violation(limits: StringLimits, message: Any) -> str | None:
    """What the plain walk of the decoded message finds first (the scans' reference)."""
    try:
        for key, value in _strings(message):
            _check_string(limits, key, value)
    except ProtocolLimitError as exc:
        return str(exc)
    return None


@settings(max_examples=600, deadline=None)
@example(message={"nodeId": 'a"' + "b" * 12}, limits=StringLimits(id_len=5), indent=None)
@example(message={"x": [{"key": "loadId", "value": "L" * 9}]}, limits=LOAD_8, indent=None)
@example(message={"mapId": ["ok", "far too long"]}, limits=StringLimits(id_len=5), indent=None)
@given(
    message=st.dictionaries(st.sampled_from(CHECKED + OTHER), values, max_size=5),
    limits=limits,
    indent=st.sampled_from([None, 1]),
)
def test_check_message_refuses_exactly_what_a_walk_of_the_whole_message_refuses(
    message: dict[str, Any], limits: StringLimits, indent: int | None
) -> None:
    """The scans only decide whether to walk: a message is refused exactly when a walk of
    it finds a string over a limit, in compact JSON and with whitespace alike."""
    payload = (
        msgspec.json.encode(message)
        if indent is None
        else json.dumps(message, indent=indent, ensure_ascii=False).encode()
    )
    expected = walked_violation(limits, message)
    if expected is None:
        check_message(limits, "uagv/v2/m/s/order", payload)
    else:
        with pytest.raises(ProtocolLimitError) as refused:
            check_message(limits, "uagv/v2/m/s/order", payload)
        assert str(refused.value) == expected
