"""The admin per role: who gets in, and what each role sees, changes and cannot touch."""

from typing import Any

import pytest
from django.test import Client

from fleet import roles
from tests.factories import VehicleFactory
from tests.security.conftest import NO_ROLE, NOBODY, PRINCIPALS, count

# principal → (page → expected status). 302 is the admin's login page.
ADMIN_PAGES = [
    "/admin/",
    "/admin/maintenance/workorder/",
    "/admin/maintenance/workorder/add/",
    "/admin/orders/transportorder/",
    "/admin/orders/transportorder/add/",
    "/admin/orders/integrationclient/",
    "/admin/orders/apitoken/",
    "/admin/robots/vehicle/",
    "/admin/robots/mqttcredential/",
    "/admin/auth/user/",
    "/admin/auth/group/",
    "/admin/fleet/auditentry/",
    "/admin/maps/map/",
]
DENIED = 403
LOGIN = 302
OK = 200
EXPECTED: dict[str, dict[str, int]] = {
    NOBODY: dict.fromkeys(ADMIN_PAGES, LOGIN),
    NO_ROLE: dict.fromkeys(ADMIN_PAGES, LOGIN),
    roles.OPERATOR: dict.fromkeys(ADMIN_PAGES, LOGIN),  # operators work in the pages only
    roles.TECHNICIAN: {
        **dict.fromkeys(ADMIN_PAGES, DENIED),
        "/admin/": OK,
        "/admin/maintenance/workorder/": OK,
        "/admin/maintenance/workorder/add/": OK,
        "/admin/robots/vehicle/": OK,  # read
    },
    roles.MANAGER: {
        **dict.fromkeys(ADMIN_PAGES, DENIED),
        "/admin/": OK,
        "/admin/maintenance/workorder/": OK,  # read
        "/admin/orders/transportorder/": OK,  # read
        "/admin/robots/vehicle/": OK,  # read
        "/admin/fleet/auditentry/": OK,  # read
    },
    roles.ADMINISTRATOR: dict.fromkeys(ADMIN_PAGES, OK),
}


@pytest.mark.parametrize("principal", PRINCIPALS)
def test_admin_per_role(principal: str, principals: dict[str, Any]) -> None:
    client = Client()
    user = principals[principal]
    if user is not None:
        client.force_login(user)
    wrong = []

    for page, expected in EXPECTED[principal].items():
        status = client.get(page).status_code
        if status != expected:
            wrong.append(f"{page}: {status}, expected {expected}")

    count("admin: principal × page", len(ADMIN_PAGES))
    assert not wrong, f"{principal}:\n  " + "\n  ".join(wrong)


def test_staff_status_alone_does_not_open_the_admin_to_an_operator(
    principals: dict[str, Any],
) -> None:
    operator = principals[roles.OPERATOR]
    operator.is_staff = True
    operator.save()
    client = Client()
    client.force_login(operator)

    assert client.get("/admin/").status_code == LOGIN


def test_a_manager_reads_but_cannot_change_in_the_admin(principals: dict[str, Any]) -> None:
    client = Client()
    client.force_login(principals[roles.MANAGER])
    vehicle = VehicleFactory()
    page = f"/admin/robots/vehicle/{vehicle.pk}/change/"

    assert client.get(page).status_code == OK
    assert client.post(page, {"serial_number": "CHANGED"}).status_code == DENIED
    assert client.get(f"/admin/robots/vehicle/{vehicle.pk}/delete/").status_code == DENIED
    vehicle.refresh_from_db()
    assert vehicle.serial_number != "CHANGED"
