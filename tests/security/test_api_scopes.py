"""The API's access matrix: every endpoint and method of /api/v1/ against a token of each scope
(and one without scopes), and against each role signed in with a session.

`fleet.api_access.ENDPOINTS` is the expectation: one scope (and user permission) per endpoint
and kind of call. Allowed means neither 401 nor 403 (missing sample objects give 404 after the
check); refused means 403, or 401 for nobody.
"""

from typing import Any

import pytest
from rest_framework.test import APIClient

from fleet import roles
from fleet.api_access import DOCUMENTATION, ENDPOINTS, rule_for
from orders import services
from tests.security.conftest import PRINCIPALS, count
from tests.security.urls import Route, sample_url, walk

API_PREFIX = "api/v1/"
WRITE_METHODS = ("post", "put", "patch", "delete")


def api_routes() -> list[Route]:
    return [route for route in walk() if route.route.startswith(API_PREFIX)]


def methods_of(route: Route) -> list[str]:
    """The HTTP methods the route's view answers (besides HEAD and OPTIONS)."""
    actions = getattr(route.view, "actions", None)
    if actions:  # a viewset route: method → action (DRF adds "head" once a GET was served)
        return sorted(method.upper() for method in actions if method not in ("head", "options"))
    view_class = route.view.cls
    return sorted(
        method.upper() for method in ("get", *WRITE_METHODS) if hasattr(view_class, method)
    )


def calls() -> list[tuple[Route, str]]:
    return [
        (route, method)
        for route in api_routes()
        if route.name not in DOCUMENTATION
        for method in methods_of(route)
    ]


def test_every_api_endpoint_and_method_has_a_scope() -> None:
    routes = api_routes()
    missing = [
        f"{method} /{route.route} ({route.name or 'no name'})"
        for route in routes
        if route.name not in DOCUMENTATION
        for method in methods_of(route)
        if rule_for(route.name, method) is None
    ]
    stale = sorted(set(ENDPOINTS) - {route.name for route in routes})

    assert not missing, (
        "These API calls have no scope in fleet/api_access.py ENDPOINTS (they are refused to "
        "everyone until they get one):\n  " + "\n  ".join(missing)
    )
    assert not stale, f"ENDPOINTS names URLs that no longer exist: {stale}"
    assert {scope for access in ENDPOINTS.values() for scope in _scopes(access)} == set(
        roles.ALL_API_SCOPES
    ), "every scope opens at least one endpoint"


def _scopes(access: Any) -> set[str]:
    return {rule.scope for rule in (access.read, access.write) if rule is not None}


def _call(client: APIClient, route: Route, method: str) -> Any:
    url = sample_url(route)
    if method == "GET":
        return client.get(url)
    return getattr(client, method.lower())(url, {}, format="json")


def _token_client(scopes: list[str], name: str) -> APIClient:
    client = services.create_integration_client(name=name, scopes=scopes)
    client_api = APIClient()
    client_api.credentials(
        HTTP_AUTHORIZATION=f"Bearer {services.issue_api_token(client=client)[1]}"
    )
    return client_api


@pytest.mark.django_db
def test_a_token_reaches_exactly_the_endpoints_of_its_scopes() -> None:
    wrong: list[str] = []
    holders = [[scope] for scope in roles.ALL_API_SCOPES] + [[]]
    api_calls = calls()

    for number, scopes in enumerate(holders):
        client = _token_client(scopes, f"scoped-{number}")
        for route, method in api_calls:
            rule = rule_for(route.name, method)
            assert rule is not None  # test_every_api_endpoint_and_method_has_a_scope says which
            status = _call(client, route, method).status_code
            allowed = status not in (401, 403)
            if allowed != (rule.scope in scopes):
                wrong.append(f"{scopes or 'no scope'}: {method} /{route.route} → {status}")

    count("API: token scope × endpoint × method", len(holders) * len(api_calls))
    assert len(api_calls) >= 50
    assert not wrong, "\n".join(wrong)


@pytest.mark.parametrize("principal", PRINCIPALS)
def test_a_signed_in_user_reaches_the_endpoints_of_their_role(
    principal: str, principals: dict[str, Any]
) -> None:
    user = principals[principal]
    client = APIClient()
    if user is not None:
        client.force_login(user)
    wrong: list[str] = []
    api_calls = calls()

    for route, method in api_calls:
        rule = rule_for(route.name, method)
        assert rule is not None
        status = _call(client, route, method).status_code
        if user is None:
            expected = "401"
            ok = status == 401
        else:
            may = rule.permission is not None and user.has_perm(rule.permission)
            expected = "allowed" if may else "403"
            ok = (status not in (401, 403)) if expected == "allowed" else status == 403
        if not ok:
            wrong.append(f"{method} /{route.route} needs {rule.permission}: {status}, {expected}")

    count("API: principal × endpoint × method", len(api_calls))
    assert not wrong, f"{principal}:\n  " + "\n  ".join(wrong)
