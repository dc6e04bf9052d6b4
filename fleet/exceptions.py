"""Domain errors and their mapping to HTTP answers for the API."""

from typing import Any

from rest_framework import status
from rest_framework.response import Response
from rest_framework.views import exception_handler


class DomainError(Exception):
    """A request that is well-formed but not allowed in the current state (HTTP 409)."""

    http_status: int = status.HTTP_409_CONFLICT


class InvalidRequestError(DomainError):
    """A request whose content cannot be carried out, such as an unreachable station (HTTP 422)."""

    http_status = status.HTTP_422_UNPROCESSABLE_ENTITY


def api_exception_handler(exc: Exception, context: dict[str, Any]) -> Response | None:
    """DRF's handler plus DomainError → 409/422 with the reason, so views need no try blocks."""
    if isinstance(exc, DomainError):
        return Response({"detail": str(exc)}, status=exc.http_status)
    return exception_handler(exc, context)
