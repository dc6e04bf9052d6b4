"""factory_boy factories for the app models."""

from typing import Any

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


def user_with_role(role: str, username: str | None = None, **fields: Any) -> Any:
    """A user holding one role of `fleet.roles` (its group, and staff when the role is): the way
    tests sign in people with the permissions they need (`client.force_login(user)`)."""
    from django.contrib.auth import get_user_model

    from fleet.roles import assign_role

    user = get_user_model().objects.create_user(username or f"{role}-user", **fields)
    assign_role(user=user, role=role)
    return user
