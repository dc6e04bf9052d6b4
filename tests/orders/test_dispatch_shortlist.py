"""The dispatch shortlist (issue 11): with a few orders and many idle vehicles a cycle checks only
the vehicles nearest to the orders, and assigns what a cycle over the whole fleet would."""

import random
from datetime import timedelta

import pytest
from django.db import transaction
from django.utils import timezone

from maps.demo import warehouse_layout
from maps.models import Map
from maps.selectors import load_graph
from maps.services import create_layout
from orders import services
from orders.models import TransportOrder
from orders.services import dispatch_factsheets, dispatch_shortlist
from robots.models import Vehicle
from tests.factories import VehicleFactory

Status = TransportOrder.Status
AISLES = [f"A{c}.{r}" for c in range(6) for r in range(4)]
FATAL = [{"errorType": "x", "errorLevel": "FATAL"}]
FACTSHEET = {"typeSpecification": {"seriesName": "bench"}}  # read only for checked vehicles


def vehicle(**fields) -> Vehicle:
    return VehicleFactory(factsheet=FACTSHEET, **fields)


@pytest.fixture(autouse=True)
def no_decoded_factsheets():
    """Which factsheets a cycle decodes shows which vehicles it checked: none before a test."""
    dispatch_factsheets.forget()
    yield
    dispatch_factsheets.forget()


def checked() -> set[int]:
    """The vehicles the cycles so far have checked (their factsheets were read)."""
    return set(dispatch_factsheets._decoded)  # noqa: SLF001


def spread(count: int, nodes: list[str]) -> list[Vehicle]:
    return [vehicle(last_node_id=nodes[n % len(nodes)]) for n in range(count)]


def test_one_order_goes_to_the_nearest_vehicle_and_only_the_nearest_are_checked(station) -> None:
    far = spread(60, [n for n in AISLES if n[1] in "345"])
    near = vehicle(last_node_id="A1.3")  # PICK-c hangs 2 m off A{c}.3
    order = TransportOrder.objects.create(source=station("PICK-1"), destination=station("DROP-1"))

    assert services.dispatch_pending_orders() == [order]

    order.refresh_from_db()
    assert order.vehicle == near
    assert near.pk in checked()
    assert len(checked()) <= 20  # the nine nearest and those as near as the ninth
    assert len(far) == 60


def test_when_the_nearest_vehicles_are_held_the_whole_fleet_is_priced(station) -> None:
    for _ in range(10):
        vehicle(last_node_id="A1.3", battery_charge=3.0)  # battery low: held back
    spread(40, [n for n in AISLES if n[1] in "45"])
    fit = vehicle(last_node_id="A2.3")
    order = TransportOrder.objects.create(source=station("PICK-1"), destination=station("DROP-1"))

    assert services.dispatch_pending_orders() == [order]

    order.refresh_from_db()
    assert order.vehicle == fit  # the nearest vehicle that may work, outside the shortlist
    assert len(checked()) > 40


def test_an_order_for_one_intended_vehicle_gets_it_however_far(station) -> None:
    spread(60, AISLES)
    intended = vehicle(last_node_id="A5.0")
    order = TransportOrder.objects.create(
        source=station("PICK-1"), destination=station("DROP-1"), intended_vehicle=intended
    )

    assert services.dispatch_pending_orders() == [order]

    order.refresh_from_db()
    assert order.vehicle == intended
    assert len(checked()) < 20


@pytest.fixture
def big_map(db) -> Map:
    """A warehouse large enough for the shortlist of a few orders: 14 × 8 aisles."""
    return create_layout(spec=warehouse_layout(columns=14, rows=8, map_id="big"))


def random_floor(rng: random.Random, layout: Map) -> None:
    """200 vehicles all over the aisles: some held back (battery low), paused, in error or busy,
    some idle for a while; then one to four new orders."""
    aisles = list(layout.nodes.filter(node_id__startswith="A").values_list("node_id", flat=True))
    picks = list(layout.stations.filter(kind="PICK"))
    drops = list(layout.stations.filter(kind="DROP"))
    vehicles = Vehicle.objects.bulk_create(
        Vehicle(
            manufacturer="sim",
            serial_number=f"AGV-{n:03d}",
            connection=Vehicle.Connection.ONLINE,
            operating_mode="AUTOMATIC",
            map_id=layout.map_id,
            last_node_id=rng.choice(aisles),
            battery_charge=rng.choice([90.0, 90.0, 90.0, 60.0, 3.0]),
            paused=rng.random() < 0.05,
            errors=FATAL if rng.random() < 0.05 else [],
            factsheet=FACTSHEET,
        )
        for n in range(200)
    )
    TransportOrder.objects.bulk_create(
        TransportOrder(
            source=rng.choice(picks),
            destination=rng.choice(drops),
            vehicle=someone,
            status=rng.choice([Status.IN_PROGRESS, Status.FINISHED]),
            finished_at=timezone.now() - timedelta(minutes=rng.randint(1, 90)),
        )
        for someone in vehicles
        if rng.random() < 0.3
    )
    for _ in range(rng.randint(1, 4)):
        TransportOrder.objects.create(
            source=rng.choice(picks),
            destination=rng.choice(drops),
            priority=rng.choice([0, 5]),
            intended_vehicle=rng.choice(vehicles) if rng.random() < 0.15 else None,
        )


def dispatched(layout: Map) -> tuple[dict[int, int], float, int]:
    """One cycle, undone afterwards: order -> vehicle, the total travel time to the pickups,
    and how many vehicles it checked."""
    dispatch_factsheets.forget()
    graph = load_graph(map=layout)
    with transaction.atomic():
        assigned = services.dispatch_pending_orders()
        pairs = {o.pk: o.vehicle_id for o in assigned}
        travel = sum(graph.travel_times_to(o.route[o.route_steps[0]])[o.route[0]] for o in assigned)
        transaction.set_rollback(True)
    return pairs, round(travel, 6), len(checked())


@pytest.mark.parametrize("seed", range(16))
def test_the_shortlist_assigns_what_the_whole_fleet_would(seed, big_map, monkeypatch) -> None:
    random_floor(random.Random(seed), big_map)

    short, short_travel, short_checked = dispatched(big_map)
    monkeypatch.setattr(dispatch_shortlist, "MAX_ORDERS", 0)  # every cycle over the whole fleet
    whole, whole_travel, whole_checked = dispatched(big_map)

    assert short.keys() == whole.keys()
    assert short_travel == whole_travel  # pairs may differ only between equally near vehicles
    if len(whole) == 1:
        assert short == whole
    if len(whole) == TransportOrder.objects.filter(status=Status.NEW).count():
        assert short_checked < whole_checked / 2  # these floors need no fallback to serve all
