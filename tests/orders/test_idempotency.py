"""Idempotency-Key on order creation, including concurrent retries over real HTTP."""

import json
import urllib.error
import urllib.request
from collections import Counter, defaultdict
from concurrent.futures import ThreadPoolExecutor
from datetime import timedelta

import pytest
from django.utils import timezone
from rest_framework.parsers import JSONParser
from rest_framework.request import Request
from rest_framework.test import APIClient, APIRequestFactory

from maps.demo import warehouse_layout
from maps.services import create_layout
from orders import services
from orders.api.idempotency import fingerprint
from orders.models import IdempotencyKey, TransportOrder

BODY = {"source": "PICK-1", "destination": "DROP-1", "external_ref": "SO-1"}


def post(api: APIClient, key: str, body: dict | None = None):
    return api.post("/api/v1/orders/", body or BODY, format="json", HTTP_IDEMPOTENCY_KEY=key)


def test_a_retry_with_the_same_key_and_body_returns_the_first_answer(api, demo_map) -> None:
    first = post(api, "k-1")
    # Same content, other key order and spacing: still the same request.
    retry = api.post(
        "/api/v1/orders/",
        json.dumps({"external_ref": "SO-1", "destination": "DROP-1", "source": "PICK-1"}),
        content_type="application/json",
        HTTP_IDEMPOTENCY_KEY="k-1",
    )

    assert first.status_code == retry.status_code == 201
    assert retry.json() == first.json()
    assert retry["Idempotent-Replayed"] == "true"
    assert "Idempotent-Replayed" not in first
    assert TransportOrder.objects.count() == 1
    stored = IdempotencyKey.objects.get()
    assert (stored.state, stored.response_status) == ("COMPLETED", 201)


def test_the_same_key_with_another_body_is_422(api, demo_map) -> None:
    post(api, "k-1")

    other = post(api, "k-1", {**BODY, "priority": 5})

    assert other.status_code == 422
    assert "different request" in other.json()["detail"]
    assert TransportOrder.objects.count() == 1


def test_a_retry_while_the_first_is_in_flight_is_409_until_it_is_abandoned(
    api, demo_map, erp
) -> None:
    request = Request(
        APIRequestFactory().post("/api/v1/orders/", BODY, format="json"), parsers=[JSONParser()]
    )
    claim = services.claim_idempotency_key(
        user=erp.user, key="k-1", request_hash=fingerprint(request), path="/api/v1/orders/"
    )

    in_flight = post(api, "k-1")
    IdempotencyKey.objects.filter(pk=claim.pk).update(
        locked_at=timezone.now() - timedelta(minutes=5)
    )
    taken_over = post(api, "k-1")

    assert in_flight.status_code == 409
    assert "in progress" in in_flight.json()["detail"]
    assert taken_over.status_code == 201
    assert TransportOrder.objects.count() == 1


def test_a_failed_request_frees_its_key(api, demo_map) -> None:
    invalid = post(api, "k-1", {**BODY, "destination": "PICK-1"})
    bad = post(api, "k-1", {"source": "PICK-1"})
    good = post(api, "k-1")

    assert (invalid.status_code, bad.status_code, good.status_code) == (422, 400, 201)
    assert IdempotencyKey.objects.get().state == "COMPLETED"


def test_keys_belong_to_one_client(api, demo_map) -> None:
    other_client = services.create_integration_client(name="wms", scopes=["orders:write"])
    other = APIClient()
    other.credentials(
        HTTP_AUTHORIZATION=f"Bearer {services.issue_api_token(client=other_client)[1]}"
    )

    assert post(api, "k-1").status_code == 201
    assert post(other, "k-1", {**BODY, "priority": 1}).status_code == 201
    assert TransportOrder.objects.count() == 2


@pytest.mark.parametrize("key", ["", "x" * 256, "tab\there", "ü"])
def test_a_malformed_key_is_400(api, demo_map, key) -> None:
    response = post(api, key)

    assert response.status_code == 400
    assert "Idempotency-Key" in response.json()
    assert not TransportOrder.objects.exists()


def test_without_a_key_every_post_creates_an_order(api, demo_map) -> None:
    api.post("/api/v1/orders/", BODY, format="json")
    api.post("/api/v1/orders/", BODY, format="json")

    assert TransportOrder.objects.count() == 2


def test_old_keys_are_pruned(api, demo_map) -> None:
    post(api, "old")
    post(api, "new")
    IdempotencyKey.objects.filter(key="old").update(created_at=timezone.now() - timedelta(days=2))

    assert services.prune_idempotency_keys() == 1
    assert list(IdempotencyKey.objects.values_list("key", flat=True)) == ["new"]


@pytest.mark.django_db(transaction=True)
def test_concurrent_retries_over_http_create_exactly_one_order_per_key(live_server) -> None:
    create_layout(spec=warehouse_layout(columns=6, rows=4))
    client = services.create_integration_client(name="erp-load", scopes=["orders:write"])
    key = services.issue_api_token(client=client)[1]
    url = f"{live_server.url}/api/v1/orders/"

    def send(idempotency_key: str) -> tuple[str, int, dict]:
        body = json.dumps({**BODY, "external_ref": idempotency_key}).encode()
        request = urllib.request.Request(
            url,
            data=body,
            method="POST",
            headers={
                "Authorization": f"Bearer {key}",
                "Content-Type": "application/json",
                "Idempotency-Key": idempotency_key,
            },
        )
        try:
            with urllib.request.urlopen(request, timeout=60) as response:  # noqa: S310
                return idempotency_key, response.status, json.loads(response.read())
        except urllib.error.HTTPError as error:
            return idempotency_key, error.code, json.loads(error.read() or b"{}")

    keys = [f"key-{n:03d}" for n in range(100) for _ in range(10)]  # each key 10× in a row
    with ThreadPoolExecutor(max_workers=10) as pool:
        answers = list(pool.map(send, keys))
        replays = list(pool.map(send, sorted(set(keys))))

    statuses = Counter(status for _, status, _ in answers)
    created: dict[str, set[int]] = defaultdict(set)
    for idempotency_key, status, body in answers + replays:
        if status == 201:
            created[idempotency_key].add(body["id"])
    assert set(statuses) <= {201, 409}, statuses
    assert TransportOrder.objects.count() == 100
    assert all(len(ids) == 1 for ids in created.values())
    assert len(created) == 100
    assert {status for _, status, _ in replays} == {201}
    assert sorted(TransportOrder.objects.values_list("external_ref", flat=True)) == sorted(
        set(keys)
    )
