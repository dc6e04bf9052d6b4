"""ERP retries (RELIABILITY.md §3 row 9, §5 "Idempotency"): K keys × 10 concurrent identical
POSTs over HTTP to the row's own web process, then every key once more (replay), the same key
with another body (422), and POSTs without a key.

Figures: orders created per key (exactly 1), answers by status, 5xx 0, replays answered 201
with the first order, key reuse with another body answered 422.
"""

from collections import Counter, defaultdict
from concurrent.futures import ThreadPoolExecutor
from typing import Any

from bench.faults.api import Api, issue_token
from bench.faults.harness import row_context


def run(*, full: bool, scale: float = 1.0) -> dict[str, Any]:
    with row_context(full=full) as context:
        from orders.models import TransportOrder

        keys = context.pick(max(10, int(100 * scale)), 1_000)
        context.fleet.web()
        api = Api(context.fleet.web_port, issue_token("erp-retries"))

        def send(key: str) -> tuple[str, int, int | None]:
            status, body, _ = api.create_order(key, "PICK-1", "DROP-1", key)
            return key, status, body.get("id") if status in (200, 201) else None

        sequence = [f"key-{n:04d}" for n in range(keys) for _ in range(10)]
        with ThreadPoolExecutor(max_workers=10) as pool:
            answers = list(pool.map(send, sequence))
            replays = list(pool.map(send, sorted(set(sequence))))
            conflicts = [
                api.request(
                    "POST",
                    "/orders/",
                    {"source": "PICK-2", "destination": "DROP-2", "external_ref": key},
                    key,
                )[0]
                for key in sorted(set(sequence))[:20]
            ]
        without_key = [
            api.create_order(None, "PICK-1", "DROP-1", f"nokey-{n}")[0] for n in range(5)
        ]
        created: dict[str, set[int]] = defaultdict(set)
        for key, _status, order_id in answers + replays:
            if order_id is not None:
                created[key].add(order_id)
        statuses = Counter(status for _, status, _ in answers)
        keyed = TransportOrder.objects.exclude(external_ref__startswith="nokey-")
        per_key = Counter(keyed.values_list("external_ref", flat=True))
        figures: dict[str, Any] = {
            "keys": keys,
            "posts": len(answers),
            "answers_by_status": {str(k): v for k, v in sorted(statuses.items())},
            "orders_created": keyed.count(),
            "keys_with_one_order": sum(1 for v in per_key.values() if v == 1),
            "keys_with_several_orders": sum(1 for v in per_key.values() if v > 1),
            "http_5xx": sum(v for k, v in statuses.items() if k >= 500),
            "replays_201_same_order": sum(
                1 for key, status, oid in replays if status == 201 and created[key] == {oid}
            ),
            "reuse_other_body": dict(Counter(conflicts)),
            "without_key": dict(Counter(without_key)),
        }
        figures["passed"] = bool(
            figures["orders_created"] == keys
            and figures["keys_with_one_order"] == keys
            and figures["http_5xx"] == 0
            and figures["replays_201_same_order"] == keys
            and set(conflicts) == {422}
            and set(without_key) == {201}
            and set(statuses) <= {201, 409}
        )
        return figures
