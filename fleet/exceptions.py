"""Domain errors and their mapping to HTTP answers for the API."""

import logging
from typing import Any

from django.db import DataError, InterfaceError, OperationalError
from rest_framework import status
from rest_framework.response import Response
from rest_framework.views import exception_handler

logger = logging.getLogger(__name__)


class DomainError(Exception):
    """A request that is well-formed but not allowed in the current state (HTTP 409)."""

    http_status: int = status.HTTP_409_CONFLICT


class InvalidRequestError(DomainError):
    """A request whose content cannot be carried out, such as an unreachable station (HTTP 422)."""

    http_status = status.HTTP_422_UNPROCESSABLE_ENTITY


def api_exception_handler(exc: Exception, context: dict[str, Any]) -> Response | None:
    """DRF's handler plus DomainError → 409/422 with the reason, so views need no try blocks,
    a value the database cannot take (a NUL character in a query parameter, say) → 400, and a
    database outage → 503 with Retry-After (the client retries; nothing was written)."""
    if isinstance(exc, DomainError):
        return Response({"detail": str(exc)}, status=exc.http_status)
    if isinstance(exc, DataError):  # the request's transaction is rolled back: nothing written
        logger.info("refused request data in %s: %s", context.get("view"), exc)
        reason = str(exc).splitlines()[0][:200] if str(exc) else "invalid value"
        return Response(
            {"detail": f"The request holds a value the database cannot take: {reason}"},
            status=status.HTTP_400_BAD_REQUEST,
        )
    if isinstance(exc, OperationalError | InterfaceError):
        from fleet.middleware import RETRY_AFTER_SECONDS

        logger.warning("database error in %s: %r", context.get("view"), exc)
        return Response(
            {"detail": "The database is unavailable; retry later."},
            status=status.HTTP_503_SERVICE_UNAVAILABLE,
            headers={"Retry-After": str(RETRY_AFTER_SECONDS)},
        )
    return exception_handler(exc, context)
