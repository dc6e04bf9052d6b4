"""The view side of `Idempotency-Key` (see `orders.services.idempotency` for the protocol)."""

import hashlib
import json
from collections.abc import Callable
from typing import Any

from django.contrib.auth.models import User
from django.db import transaction
from drf_spectacular.utils import OpenApiParameter
from rest_framework.exceptions import NotAuthenticated, ValidationError
from rest_framework.request import Request
from rest_framework.response import Response

from orders import services

HEADER = "Idempotency-Key"
REPLAYED_HEADER = "Idempotent-Replayed"

PARAMETER = OpenApiParameter(
    HEADER,
    str,
    OpenApiParameter.HEADER,
    description=(
        "Any unique string (a UUID, say) of 1-255 printable ASCII characters. A retry with the "
        "same key and body returns the first response again (with the header "
        "`Idempotent-Replayed: true`); while the first request is still running a retry gets "
        "409, and the same key with a different body 422. Keys are kept for 24 hours."
    ),
)


class _Failed(Exception):
    def __init__(self, response: Response) -> None:
        self.response = response


def idempotent(request: Request, perform: Callable[[], Response]) -> Response:
    """Run `perform` at most once per Idempotency-Key of the requesting user (without the header,
    just run it). Only successful responses are stored; after a failure the key is free again."""
    key = request.headers.get(HEADER)
    if key is None:
        return perform()
    if not 1 <= len(key) <= 255 or not (key.isascii() and key.isprintable()):
        raise ValidationError({HEADER: ["Use 1 to 255 printable ASCII characters."]})
    if not isinstance(request.user, User):
        raise NotAuthenticated()
    claim = services.claim_idempotency_key(
        user=request.user, key=key, request_hash=fingerprint(request), path=request.path[:200]
    )
    if isinstance(claim, services.StoredResponse):
        return Response(claim.body, status=claim.status, headers={REPLAYED_HEADER: "true"})
    try:
        with transaction.atomic():
            response = perform()
            if response.status_code >= 400:
                raise _Failed(response)
            services.complete_idempotency_key(
                claim=claim, status=response.status_code, body=response.data
            )
    except _Failed as failed:
        services.release_idempotency_key(claim=claim)
        return failed.response
    except BaseException:
        services.release_idempotency_key(claim=claim)
        raise
    return response


def fingerprint(request: Request) -> str:
    """SHA-256 of the method, the path and the parsed body (so key order and spacing of the JSON
    do not matter)."""
    data: Any = request.data
    if hasattr(data, "lists"):  # a QueryDict from a form
        data = dict(data.lists())
    canonical = json.dumps([request.method, request.path, data], sort_keys=True, default=str)
    return hashlib.sha256(canonical.encode()).hexdigest()
