"""The transport order endpoints and token authentication."""

from datetime import timedelta

import pytest
from django.utils import timezone
from rest_framework.test import APIClient

from orders import services
from orders.models import TransportOrder
from tests.factories import VehicleFactory, user_with_role

Status = TransportOrder.Status


def create(api: APIClient, **body) -> dict:
    body = {"source": "PICK-1", "destination": "DROP-1", **body}
    response = api.post("/api/v1/orders/", body, format="json")
    assert response.status_code == 201, response.content
    return response.json()


def test_post_creates_an_order_by_station_ids(api, demo_map, erp) -> None:
    start = timezone.now() + timedelta(minutes=5)
    response = api.post(
        "/api/v1/orders/",
        {
            "source": "PICK-1",
            "destination": "DROP-3",
            "load_id": "PAL-7",
            "external_ref": "SO-1",
            "priority": 3,
            "earliest_start": start.isoformat(),
            "deadline": (start + timedelta(hours=1)).isoformat(),
        },
        format="json",
    )

    body = response.json()
    assert response.status_code == 201, body
    assert (body["status"], body["source"], body["destination"], body["map"]) == (
        "NEW",
        "PICK-1",
        "DROP-3",
        "demo",
    )
    assert body["events"][0]["kind"] == "CREATED"
    assert body["events"][0]["detail"] == {"by": "client:erp"}
    order = TransportOrder.objects.get()
    assert (order.load_id, order.priority, order.created_by) == ("PAL-7", 3, erp.user)
    assert order.earliest_start == start


def test_the_answer_to_a_post_reads_its_steps_at_once(
    api, demo_map, django_assert_num_queries
) -> None:
    """The answer is rendered inside the order's transaction: a read per step delayed dispatch."""

    def queries(stations: list[str]) -> int:
        from django.db import connection
        from django.test.utils import CaptureQueriesContext

        steps = [{"station": s, "operation": "PICK"} for s in stations[:-1]]
        steps.append({"station": stations[-1], "operation": "DROP"})
        with CaptureQueriesContext(connection) as captured:
            response = api.post("/api/v1/orders/", {"steps": steps}, format="json")
        assert response.status_code == 201, response.content
        assert [s["station"] for s in response.json()["steps"]] == stations
        return len(captured.captured_queries)

    queries(["PICK-1", "DROP-1"])  # the routing graph's first build
    two = queries(["PICK-1", "DROP-1"])
    four = queries(["PICK-1", "PICK-2", "PICK-3", "DROP-1"])
    assert four == two


@pytest.mark.parametrize(
    ("body", "field"),
    [
        ({"source": "NOPE", "destination": "DROP-1"}, "source"),
        ({"source": "PICK-1"}, "destination"),
        ({"source": "PICK-1", "destination": "DROP-1", "priority": "high"}, "priority"),
        ({"source": "PICK-1", "destination": "DROP-1", "priority": 5000}, "priority"),
        ({"source": "PICK-1", "destination": "DROP-1", "deadline": "soon"}, "deadline"),
        ({"source": "PICK-1", "destination": "DROP-1", "map": "elsewhere"}, "source"),
        ({"source": "PICK-1", "destination": "DROP-1", "load_id": "x" * 101}, "load_id"),
    ],
)
def test_bad_input_gets_400_with_the_field_and_writes_nothing(api, demo_map, body, field) -> None:
    response = api.post("/api/v1/orders/", body, format="json")

    assert response.status_code == 400
    assert field in response.json()
    assert not TransportOrder.objects.exists()


@pytest.mark.parametrize(
    ("body", "reason"),
    [
        ({"destination": "PICK-1"}, "same station"),
        (
            {
                "earliest_start": "2030-01-01T10:00:00Z",
                "deadline": "2030-01-01T09:00:00Z",
            },
            "deadline must be later",
        ),
    ],
)
def test_requests_that_cannot_be_carried_out_are_422(api, demo_map, body, reason) -> None:
    response = api.post(
        "/api/v1/orders/", {"source": "PICK-1", "destination": "DROP-1", **body}, format="json"
    )

    assert response.status_code == 422
    assert reason in response.json()["detail"]
    assert not TransportOrder.objects.exists()


def test_get_shows_one_order_with_its_timeline_and_404_for_unknown(api, demo_map) -> None:
    created = create(api)

    shown = api.get(f"/api/v1/orders/{created['id']}/")

    assert shown.status_code == 200
    assert shown.json()["id"] == created["id"]
    assert shown.json()["dispatch_note"] == ""
    assert api.get("/api/v1/orders/999999/").status_code == 404
    assert api.get("/api/v1/orders/99999999999999999999999/").status_code == 404


def test_list_filters(api, demo_map, station) -> None:
    vehicle = VehicleFactory(serial_number="V-9")
    first = create(api, external_ref="SO-1")
    second = create(api, source="PICK-2", destination="DROP-2", external_ref="SO-2")
    TransportOrder.objects.filter(pk=second["id"]).update(
        status=Status.FINISHED, vehicle=vehicle, finished_at=timezone.now()
    )
    ids = lambda query: [o["id"] for o in api.get(f"/api/v1/orders/?{query}").json()["results"]]  # noqa: E731
    an_hour_ago = (timezone.now() - timedelta(hours=1)).strftime("%Y-%m-%dT%H:%M:%SZ")

    assert ids("") == [second["id"], first["id"]]
    assert ids("status=new") == [first["id"]]
    assert ids("status=FINISHED") == [second["id"]]
    assert ids("vehicle=V-9") == [second["id"]]
    assert ids(f"vehicle_id={vehicle.pk}") == [second["id"]]
    assert ids("source=PICK-1") == [first["id"]]
    assert ids("destination=DROP-2") == [second["id"]]
    assert ids("external_ref=SO-1") == [first["id"]]
    assert ids(f"created_after={an_hour_ago}") == [second["id"], first["id"]]
    assert ids(f"created_before={an_hour_ago}") == []
    assert ids(f"finished_after={an_hour_ago}") == [second["id"]]
    assert ids(f"finished_before={an_hour_ago}") == []
    assert api.get("/api/v1/orders/?status=lost").status_code == 400
    assert api.get("/api/v1/orders/?created_after=yesterday").status_code == 400


def test_list_is_paginated_with_bounds(api, demo_map, django_assert_max_num_queries) -> None:
    for _ in range(3):
        create(api)

    with django_assert_max_num_queries(7):  # auth, count, page, events, steps
        page = api.get("/api/v1/orders/?limit=2").json()
    last = api.get("/api/v1/orders/?limit=2&offset=2").json()
    huge = api.get("/api/v1/orders/?limit=99999999999&offset=999999999999999999999")

    assert page["count"] == 3
    assert len(page["results"]) == 2
    assert page["next"]
    assert len(last["results"]) == 1
    assert huge.status_code == 200
    assert huge.json()["results"] == []


def test_cancel_and_cancel_of_a_closed_order_is_409(api, demo_map) -> None:
    created = create(api)

    cancelled = api.post(f"/api/v1/orders/{created['id']}/cancel/", {"reason": "x"}, format="json")
    again = api.post(f"/api/v1/orders/{created['id']}/cancel/", {}, format="json")

    assert cancelled.status_code == 200
    assert cancelled.json()["status"] == "CANCELLED"
    assert again.status_code == 409
    assert "cannot be cancelled" in again.json()["detail"]
    assert api.post("/api/v1/orders/424242/cancel/", {}, format="json").status_code == 404


def test_priority_and_deadline_change_while_open(api, demo_map) -> None:
    created = create(api)
    deadline = (timezone.now() + timedelta(hours=2)).replace(microsecond=0)

    changed = api.post(
        f"/api/v1/orders/{created['id']}/priority/",
        {"priority": 7, "deadline": deadline.isoformat()},
        format="json",
    )
    cleared = api.post(
        f"/api/v1/orders/{created['id']}/priority/",
        {"priority": 7, "deadline": None},
        format="json",
    )

    assert changed.status_code == 200, changed.content
    assert changed.json()["priority"] == 7
    assert changed.json()["events"][-1]["kind"] == "UPDATED"
    assert changed.json()["events"][-1]["detail"]["priority"] == [0, 7]
    assert cleared.json()["deadline"] is None
    assert TransportOrder.objects.get().priority == 7
    assert (
        api.post(f"/api/v1/orders/{created['id']}/priority/", {}, format="json").status_code == 400
    )
    api.post(f"/api/v1/orders/{created['id']}/cancel/", {}, format="json")
    closed = api.post(f"/api/v1/orders/{created['id']}/priority/", {"priority": 1}, format="json")
    assert closed.status_code == 409


def test_anonymous_requests_get_401_with_a_bearer_challenge(demo_map) -> None:
    response = APIClient().get("/api/v1/orders/")

    assert response.status_code == 401
    assert response["WWW-Authenticate"].startswith("Bearer")


def test_tokens_that_are_wrong_revoked_expired_or_of_a_disabled_client_are_refused(
    demo_map, erp
) -> None:
    token, key = services.issue_api_token(client=erp)
    _, expired_key = services.issue_api_token(
        client=erp, expires_at=timezone.now() - timedelta(seconds=1)
    )
    client = APIClient()

    def status(authorization: str) -> int:
        client.credentials(HTTP_AUTHORIZATION=authorization)
        return client.get("/api/v1/orders/").status_code

    assert status(f"Bearer {key}") == 200
    assert status(f"Token {key}") == 200
    assert status("Bearer wrong") == 401
    assert status("Bearer") == 401
    assert status(f"Bearer {expired_key}") == 401
    services.revoke_api_token(token=token)
    assert status(f"Bearer {key}") == 401
    token.refresh_from_db()
    assert token.last_used_at is not None
    _, fresh = services.issue_api_token(client=erp)
    erp.is_active = False
    erp.save()
    assert status(f"Bearer {fresh}") == 401


def test_the_token_key_is_stored_only_as_a_hash(erp) -> None:
    token, key = services.issue_api_token(client=erp)

    assert key.startswith("oft_")
    assert key not in token.key_hash
    assert token.prefix == key[:12]


def test_browser_sessions_still_work(db, demo_map) -> None:
    staff = user_with_role("operator", "staff", password="pw-123456")
    browser = APIClient()
    browser.force_login(staff)  # a session cookie, as a browser has after the login form

    assert browser.get("/api/v1/orders/").status_code == 200


def test_steps_name_the_field_of_an_unknown_or_ambiguous_station(api, demo_map) -> None:
    from maps.demo import warehouse_layout
    from maps.services import create_layout

    create_layout(spec=warehouse_layout(columns=4, rows=3, map_id="hall-2"))  # same station ids
    steps = [
        {"station": "PICK-1", "operation": "PICK"},
        {"station": "NOPE", "operation": "DROP"},
    ]

    unknown = api.post("/api/v1/orders/", {"steps": steps, "map": "demo"}, format="json")
    ambiguous = api.post("/api/v1/orders/", {"steps": steps[:1] * 2}, format="json")
    steps[1]["station"] = "DROP-1"
    chosen = api.post("/api/v1/orders/", {"steps": steps, "map": "hall-2"}, format="json")

    assert unknown.status_code == 400
    assert unknown.json() == {"steps[1].station": ["No station 'NOPE'."]}
    assert ambiguous.status_code == 400
    assert ambiguous.json() == {"steps[0].station": ["'PICK-1' is on several maps: give map."]}
    assert chosen.status_code == 201, chosen.content
    order = TransportOrder.objects.get()
    assert {s.station.map.map_id for s in order.steps.all()} == {"hall-2"}
