"""The role matrix of the pages: every principal (nobody, a user without a role, each role)
against every page and action of the site (not the admin and the API: their own tests).

`PAGES` says, per URL name and method, what it needs: a permission of `fleet.roles`, PUBLIC or
SIGNED_IN. A URL that is missing here fails `test_every_page_has_an_expectation`, so a new page
cannot arrive unprotected unnoticed. Allowed means: neither 401/403 nor the login page (a
missing sample object gives 404 *after* the check); refused means 403 for a signed-in user and
the login page (or 401/403) for nobody.
"""

from dataclasses import dataclass, field
from typing import Any

import pytest
from django.conf import settings
from django.shortcuts import resolve_url
from django.test import Client

from fleet import roles
from tests.factories import VehicleFactory
from tests.security.conftest import PRINCIPALS, count
from tests.security.urls import Route, sample_url, walk

PUBLIC = "public"
SIGNED_IN = "signed in"
LOGS_OUT = "logs out"  # anyone may, and lands on the login page

OPS = roles.VIEW_OPERATIONS

PAGES: dict[tuple[str, str], str] = {
    # fleet
    ("audit", "GET"): roles.VIEW_AUDIT,
    ("audit-csv", "GET"): roles.VIEW_AUDIT,
    ("media", "GET"): OPS,
    # accounts (Django's login, logout and password pages)
    ("login", "GET"): PUBLIC,
    ("logout", "POST"): LOGS_OUT,
    ("password_change", "GET"): SIGNED_IN,
    ("password_change_done", "GET"): SIGNED_IN,
    ("password_reset", "GET"): PUBLIC,
    ("password_reset_done", "GET"): PUBLIC,
    ("password_reset_confirm", "GET"): PUBLIC,
    ("password_reset_complete", "GET"): PUBLIC,
    # live page, operations, vehicle page
    ("control:live", "GET"): OPS,
    ("control:vehicles-json", "GET"): OPS,
    ("control:orders-json", "GET"): OPS,
    ("control:health", "GET"): PUBLIC,
    ("control:ready", "GET"): PUBLIC,  # readiness for load balancers
    ("metrics", "GET"): PUBLIC,  # Prometheus: its own network/token check (loopback here)
    ("control:overview", "GET"): OPS,
    ("control:vehicles", "GET"): OPS,
    ("control:vehicle-detail", "GET"): OPS,
    ("control:vehicle-command", "POST"): OPS,  # and each action its own, see ACTIONS
    # orders
    ("orders:list", "GET"): OPS,
    ("orders:create", "GET"): roles.OPERATE_ORDERS,
    ("orders:create", "POST"): roles.OPERATE_ORDERS,
    ("orders:cancel", "POST"): roles.OPERATE_ORDERS,
    ("orders:priority", "POST"): roles.OPERATE_ORDERS,
    ("orders:reassign", "POST"): roles.OPERATE_ORDERS,
    ("orders:recurring", "GET"): OPS,
    ("orders:recurring", "POST"): roles.OPERATE_ORDERS,
    # alerts
    ("alerts:list", "GET"): OPS,
    ("alerts:banner", "GET"): OPS,
    ("alerts:action", "POST"): roles.ACKNOWLEDGE_ALERTS,
    # energy
    ("battery:overview", "GET"): OPS,
    ("battery:vehicle", "GET"): OPS,
    # maintenance
    ("maintenance:overview", "GET"): OPS,
    ("maintenance:vehicle", "GET"): OPS,
    ("maintenance:vehicle_service", "POST"): roles.MAINTAIN_VEHICLES,
    ("maintenance:work_order", "GET"): OPS,
    ("maintenance:work_order", "POST"): roles.MAINTAIN_VEHICLES,
    # inventory
    ("inventory:stock", "GET"): OPS,
    ("inventory:export", "GET"): OPS,
    ("inventory:import", "POST"): roles.ADMINISTER,
    # layouts
    ("maps:list", "GET"): roles.MANAGE_LAYOUTS,
    ("maps:list", "POST"): roles.MANAGE_LAYOUTS,
    ("maps:edit", "GET"): roles.MANAGE_LAYOUTS,
    ("maps:check", "POST"): roles.MANAGE_LAYOUTS,
    ("maps:save", "POST"): roles.MANAGE_LAYOUTS,
    ("maps:floor-plan", "GET"): roles.MANAGE_LAYOUTS,
    ("maps:release-file", "GET"): PUBLIC,  # vehicles download with the unguessable token
    # reports
    ("reports:page", "GET"): roles.VIEW_REPORTS,
    ("reports:csv", "GET"): roles.VIEW_REPORTS,
}

# URL names whose JSON body the view reads (sent as application/json).
JSON_BODIES = {"maps:check", "maps:save", "control:vehicle-command"}

# Routes with their own tests: the admin (test_admin.py), the API (test_api_scopes.py).
OWN_TESTS = ("admin/", "api/v1/")


@dataclass(frozen=True)
class Check:
    """One request: URL name, method and what it needs; `body` for actions in the body."""

    name: str
    method: str
    needs: str
    body: dict[str, Any] = field(default_factory=dict)
    query: str = ""
    real_vehicle: bool = False  # the URL names an existing vehicle (the action runs)


# Actions decided inside one URL: the vehicle page's buttons, and the orders list view.
ACTIONS = [
    Check("control:vehicle-command", "POST", roles.COMMAND_VEHICLES, {"action": "pause"}, "", True),
    Check(
        "control:vehicle-command", "POST", roles.COMMAND_VEHICLES, {"action": "resume"}, "", True
    ),
    Check(
        "control:vehicle-command",
        "POST",
        roles.SEND_TO_CHARGE_OR_PARK,
        {"action": "park"},
        "",
        True,
    ),
    Check("orders:list", "GET", OPS, query="?view=list"),
]

CHECKS = [Check(name, method, needs) for (name, method), needs in PAGES.items()] + ACTIONS


def site_routes() -> list[Route]:
    return [route for route in walk() if not route.route.startswith(OWN_TESTS)]


def test_every_page_has_an_expectation() -> None:
    routes = site_routes()
    expected = {name for name, _ in PAGES}
    missing = [
        f"{route.name or '(no name)'}  /{route.route}"
        for route in routes
        if not route.name or route.name not in expected
    ]
    stale = sorted(expected - {route.name for route in routes})

    assert not missing, (
        "These URLs have no expectation in tests/security/test_pages.py PAGES; add one line per "
        "method, e.g. ('control:new-page', 'GET'): roles.VIEW_OPERATIONS, and protect the view "
        "(fleet.access.require_permission or login_required + permission_required):\n  "
        + "\n  ".join(missing)
    )
    assert not stale, f"PAGES names URLs that no longer exist: {stale}"


@pytest.mark.parametrize("principal", PRINCIPALS)
def test_role_matrix_of_pages(principal: str, principals: dict[str, Any]) -> None:
    user = principals[principal]
    client = Client()
    if user is not None:
        client.force_login(user)
    routes = {route.name: route for route in site_routes()}
    vehicle = VehicleFactory(manufacturer="sim", serial_number="AGV-MATRIX")
    wrong: list[str] = []

    for check in CHECKS:
        if check.name not in routes:
            continue  # reported by test_every_page_has_an_expectation
        if check.real_vehicle:
            url = sample_url(routes[check.name], serial=vehicle.serial_number)
        else:
            url = sample_url(routes[check.name])
        response = _request(_logged_out_after(client, user, check), check, url + check.query)
        outcome = _outcome(response)
        should = _expected(check.needs, user)
        if outcome not in should:
            wrong.append(
                f"{check.method} {url}{check.query} {check.body or ''} ({check.name}, needs "
                f"{check.needs}): {response.status_code} means {outcome}, expected "
                + " or ".join(sorted(should))
            )

    count("pages: principal × URL × method", len(CHECKS))
    assert not wrong, f"{principal}:\n  " + "\n  ".join(wrong)


def test_the_matrix_covers_every_role_and_page() -> None:
    assert len(PRINCIPALS) == 6
    assert len(CHECKS) >= 55
    # Every role is allowed something and refused something (no role is all or nothing,
    # except the administrator who holds every permission).
    for role in (roles.OPERATOR, roles.TECHNICIAN, roles.MANAGER):
        held = roles.ROLE_PERMISSIONS[role]
        needs = {check.needs for check in CHECKS} - {PUBLIC, SIGNED_IN, LOGS_OUT}
        assert needs & held, role
        assert needs - held, role


def _logged_out_after(client: Client, user: Any, check: Check) -> Client:
    """Logging out ends the session: that check gets a client of its own."""
    if check.needs != LOGS_OUT:
        return client
    own = Client()
    if user is not None:
        own.force_login(user)
    return own


def _request(client: Client, check: Check, url: str) -> Any:
    if check.method == "GET":
        return client.get(url)
    if check.name in JSON_BODIES:
        return client.post(url, check.body, content_type="application/json")
    return client.post(url, check.body)


def _outcome(response: Any) -> str:
    login = resolve_url(settings.LOGIN_URL)
    if response.status_code in (401, 403):
        return "refused"
    if response.status_code == 302 and response["Location"].startswith(login):
        return "sent to login"
    return "allowed"


def _expected(needs: str, user: Any) -> set[str]:
    if needs == PUBLIC:
        return {"allowed"}
    if needs == LOGS_OUT:
        return {"sent to login"}
    if user is None:  # pages send people to the login, JSON endpoints answer 401/403
        return {"sent to login", "refused"}
    if needs == SIGNED_IN or user.has_perm(needs):
        return {"allowed"}
    return {"refused"}
