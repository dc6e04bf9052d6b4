"""J.44: the string limits are checked on the encoded message, deep inside it too."""

import msgspec
import pytest

from control.capabilities import StringLimits
from control.limits import ProtocolLimitError, check_message


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
