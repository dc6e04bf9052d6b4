"""A database outage answers 503 Service Unavailable with Retry-After, never 500.

When PostgreSQL restarts, every query fails with OperationalError (or InterfaceError on a
connection that already broke). Nothing was written: each write is one transaction, rolled
back. The client may simply retry later (an ERP retries with its Idempotency-Key), which is what
503 + Retry-After says; a 500 would say "our bug". RELIABILITY.md §3 row 2.
"""

import logging
import sys
from collections.abc import Callable

from django.db import InterfaceError, OperationalError
from django.http import HttpRequest, HttpResponse, JsonResponse
from django.views import defaults

logger = logging.getLogger(__name__)

DATABASE_ERRORS = (OperationalError, InterfaceError)
RETRY_AFTER_SECONDS = 5


def database_unavailable(request: HttpRequest, exception: BaseException) -> HttpResponse:
    """The 503 answer: JSON for the API, plain text for pages."""
    logger.warning("database unavailable for %s %s: %s", request.method, request.path, exception)
    detail = "The database is unavailable; retry later."
    response: HttpResponse
    if request.path.startswith("/api/"):
        response = JsonResponse({"detail": detail}, status=503)
    else:
        response = HttpResponse(detail, status=503, content_type="text/plain; charset=utf-8")
    response["Retry-After"] = str(RETRY_AFTER_SECONDS)
    return response


class DatabaseUnavailableMiddleware:
    """Turns a database error raised by a view into the 503 answer."""

    def __init__(self, get_response: Callable[[HttpRequest], HttpResponse]) -> None:
        self.get_response = get_response

    def __call__(self, request: HttpRequest) -> HttpResponse:
        return self.get_response(request)

    def process_exception(self, request: HttpRequest, exception: Exception) -> HttpResponse | None:
        if isinstance(exception, DATABASE_ERRORS):
            return database_unavailable(request, exception)
        return None


def server_error(request: HttpRequest) -> HttpResponse:
    """handler500: database errors outside views (session, authentication and other middleware)
    also become 503; anything else is Django's 500 page."""
    exception = sys.exc_info()[1]
    if isinstance(exception, DATABASE_ERRORS):
        return database_unavailable(request, exception)
    return defaults.server_error(request)
