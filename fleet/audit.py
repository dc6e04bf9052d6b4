"""Recording the audit trail from services, with the actor taken from where the call came from.

Web requests (pages, admin, API) run inside `AuditMiddleware`, which remembers the request, so a
service records who and from which address without passing them down; processes without a
request (control, Celery tasks, management commands) name themselves with `acting_as`.
"""

from collections.abc import Iterator
from contextlib import contextmanager
from contextvars import ContextVar
from dataclasses import dataclass
from typing import Any

from django.conf import settings
from django.http import HttpRequest, HttpResponse

from fleet.models import AuditEntry


@dataclass(frozen=True)
class Actor:
    """Who gave a command: a name, the user if any, and where it came from."""

    name: str
    user_id: int | None = None
    source: str = ""


_request: ContextVar[HttpRequest | None] = ContextVar("audit_request", default=None)
_actor: ContextVar[Actor | None] = ContextVar("audit_actor", default=None)


@contextmanager
def acting_as(name: str, *, source: str = "") -> Iterator[None]:
    """Record what happens inside as done by a process (e.g. `system:dispatch`)."""
    token = _actor.set(Actor(name=name, source=source))
    try:
        yield
    finally:
        _actor.reset(token)


def client_address(request: HttpRequest) -> str:
    """The client's address (the first X-Forwarded-For hop behind a trusted proxy)."""
    if getattr(settings, "SECURE_PROXY_SSL_HEADER", None):
        forwarded = str(request.META.get("HTTP_X_FORWARDED_FOR", ""))
        if forwarded:
            return forwarded.split(",")[0].strip()[:100]
    return str(request.META.get("REMOTE_ADDR", ""))[:100]


def current_actor() -> Actor:
    """The actor of the current request or process; `system:unknown` if nobody said."""
    request = _request.get()
    if request is not None:
        user = getattr(request, "user", None)
        if user is not None and user.is_authenticated:
            return Actor(user.get_username(), user.pk, client_address(request))
        return Actor("anonymous", None, client_address(request))
    return _actor.get() or Actor("system:unknown")


def record(
    action: str,
    *,
    target_type: str = "",
    target_id: object = "",
    detail: dict[str, Any] | None = None,
) -> AuditEntry:
    """Append one entry for `action` on the target, by the current actor."""
    actor = current_actor()
    return AuditEntry.objects.create(
        actor=actor.name[:150],
        user_id=actor.user_id,
        source=actor.source,
        action=action,
        target_type=target_type,
        target_id=str(target_id)[:100],
        detail=detail or {},
    )


class AuditMiddleware:
    """Makes the request (and so its user, resolved late for API tokens) the audit actor."""

    def __init__(self, get_response: Any) -> None:
        self.get_response = get_response

    def __call__(self, request: HttpRequest) -> HttpResponse:
        token = _request.set(request)
        try:
            response: HttpResponse = self.get_response(request)
            return response
        finally:
            _request.reset(token)
