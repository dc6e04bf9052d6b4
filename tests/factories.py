"""factory_boy factories for the app models."""

import factory

from robots.models import Vehicle


class VehicleFactory(factory.django.DjangoModelFactory[Vehicle]):
    class Meta:
        model = Vehicle

    manufacturer = "sim"
    serial_number = factory.Sequence(lambda n: f"AGV-{n:03d}")
    connection = Vehicle.Connection.ONLINE
    operating_mode = "AUTOMATIC"
    map_id = "demo"
    last_node_id = "A0.0"
    battery_charge = 90.0
