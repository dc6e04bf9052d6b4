"""A database outage answers 503 with Retry-After (never 500), for the API, pages and errors
raised outside views (regression: the API answered 500 while PostgreSQL restarted)."""

import json

import pytest
from django.db import InterfaceError, OperationalError
from django.test import RequestFactory

from fleet.exceptions import api_exception_handler
from fleet.middleware import DatabaseUnavailableMiddleware, server_error


def never_called(request: object) -> None:
    raise AssertionError("not reached")


@pytest.mark.parametrize("error", [OperationalError, InterfaceError])
def test_the_api_answers_503_with_retry_after(error: type[Exception]) -> None:
    response = api_exception_handler(error("connection refused"), {})

    assert response is not None
    assert response.status_code == 503
    assert response["Retry-After"] == "5"
    assert "retry" in response.data["detail"]


def test_a_page_whose_view_hits_a_dead_database_answers_503() -> None:
    request = RequestFactory().get("/orders/")
    middleware = DatabaseUnavailableMiddleware(never_called)

    response = middleware.process_exception(request, OperationalError("server closed"))

    assert response is not None
    assert response.status_code == 503
    assert response["Retry-After"] == "5"
    assert response["Content-Type"].startswith("text/plain")


def test_other_errors_are_left_to_django() -> None:
    request = RequestFactory().get("/orders/")

    assert (
        DatabaseUnavailableMiddleware(never_called).process_exception(request, ValueError("bug"))
        is None
    )
    assert api_exception_handler(ValueError("bug"), {}) is None


def test_a_database_error_outside_a_view_becomes_503_not_the_500_page() -> None:
    request = RequestFactory().get("/api/v1/orders/")
    try:
        raise OperationalError("terminating connection due to administrator command")
    except OperationalError:
        response = server_error(request)

    assert response.status_code == 503
    assert response["Retry-After"] == "5"
    assert json.loads(response.content) == {"detail": "The database is unavailable; retry later."}


def test_any_other_error_outside_a_view_is_still_a_500() -> None:
    request = RequestFactory().get("/orders/")
    try:
        raise ValueError("bug")
    except ValueError:
        response = server_error(request)

    assert response.status_code == 500
