"""Order sequences: orders one vehicle does in turn, in the order they were posted."""

from maps.models import Station
from orders import services
from orders.models import OrderSequence, TransportOrder
from tests.factories import VehicleFactory

Status = TransportOrder.Status


def order(pick: str, drop: str, **fields) -> TransportOrder:  # type: ignore[no-untyped-def]
    return services.create_transport_order(
        source=Station.objects.get(station_id=pick),
        destination=Station.objects.get(station_id=drop),
        **fields,
    )


def refreshed(*orders: TransportOrder) -> list[TransportOrder]:
    return [TransportOrder.objects.select_related("vehicle").get(pk=o.pk) for o in orders]


def test_a_sequence_is_done_in_turn_by_the_vehicle_that_started_it(demo_map) -> None:
    first_vehicle = VehicleFactory(last_node_id="A1.3")  # next to PICK-1
    other = VehicleFactory(last_node_id="A4.3")  # next to PICK-4
    one = order("PICK-1", "DROP-1", sequence="TOUR-7")
    two = order("PICK-4", "DROP-4", sequence="TOUR-7")
    stranger = order("PICK-2", "DROP-2")

    services.dispatch_pending_orders()
    one, two, stranger = refreshed(one, two, stranger)

    assert (one.sequence_index, two.sequence_index) == (0, 1)
    assert one.vehicle == first_vehicle
    assert (two.status, two.dispatch_note) == (
        Status.NEW,
        f"waits for order {one.pk} of its sequence",
    )
    assert stranger.vehicle == other
    assert OrderSequence.objects.get().vehicle == first_vehicle

    # The first order is done; the other vehicle is idle again and nearer to PICK-4, yet the
    # sequence's vehicle gets the next order, and nothing else gets that vehicle meanwhile.
    services.mark_order_finished(order_id=stranger.pk)
    services.mark_order_finished(order_id=one.pk)
    late = order("PICK-1", "DROP-1")
    services.dispatch_pending_orders()
    two, late = refreshed(two, late)

    assert two.vehicle == first_vehicle
    assert late.vehicle == other


def test_the_vehicle_of_an_open_sequence_takes_no_other_work(demo_map) -> None:
    bound = VehicleFactory(last_node_id="A1.3")
    one = order("PICK-1", "DROP-1", sequence="TOUR-8")
    order("PICK-4", "DROP-4", sequence="TOUR-8")
    services.dispatch_pending_orders()
    services.mark_order_finished(order_id=one.pk)
    OrderSequence.objects.update(vehicle=bound)
    TransportOrder.objects.filter(sequence_index=1).update(earliest_start="2999-01-01T00:00Z")
    stranger = order("PICK-2", "DROP-2")

    services.dispatch_pending_orders()

    stranger.refresh_from_db()
    assert stranger.status == Status.NEW
    assert stranger.dispatch_note == "the idle vehicles are reserved for order sequences"


def test_the_api_takes_and_shows_the_sequence(api, demo_map) -> None:
    body = {"source": "PICK-1", "destination": "DROP-1", "sequence": "TOUR-9"}

    first = api.post("/api/v1/orders/", body, format="json").json()
    second = api.post("/api/v1/orders/", body, format="json").json()

    assert [(o["sequence"], o["sequence_index"]) for o in (first, second)] == [
        ("TOUR-9", 0),
        ("TOUR-9", 1),
    ]
