"""Who may call which REST API endpoint: the scope an integration client's token needs, and the
permission a signed-in user needs for the same call.

Every endpoint of /api/v1/ is listed here by URL name, with one rule for reading (GET, HEAD,
OPTIONS) and one for changing (POST, PUT, PATCH, DELETE). `ScopedAccess` (the default DRF
permission class) refuses what is not listed, so a new endpoint is closed until it gets a line
here (tests/security checks that every endpoint has one). Scopes and their user permissions are
defined in `fleet.roles.API_SCOPES`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from rest_framework.permissions import SAFE_METHODS, BasePermission
from rest_framework.request import Request

from fleet import roles


@dataclass(frozen=True)
class Rule:
    """One kind of call: the token scope, and the permission a signed-in user needs instead
    (None: integration clients only, signed-in users are refused)."""

    scope: str
    permission: str | None


@dataclass(frozen=True)
class Access:
    """The rules of one endpoint; None: that kind of call does not exist there."""

    read: Rule | None = None
    write: Rule | None = None

    def rule(self, method: str) -> Rule | None:
        return self.read if method in SAFE_METHODS else self.write


def scope(name: str, *, permission: str | None = None) -> Rule:
    """The rule of scope `name`; a user needs the scope's permission unless told otherwise."""
    return Rule(name, permission or roles.API_SCOPES[name][1])


ORDERS_READ, ORDERS_WRITE = scope("orders:read"), scope("orders:write")
VEHICLES_READ, VEHICLES_COMMAND = scope("vehicles:read"), scope("vehicles:command")
CHARGE_OR_PARK = scope("vehicles:command", permission=roles.SEND_TO_CHARGE_OR_PARK)
LAYOUTS_READ, LAYOUTS_WRITE = scope("layouts:read"), scope("layouts:write")
WEBHOOKS = scope("webhooks:manage")  # a client's own subscriptions: clients only

ENDPOINTS: dict[str, Access] = {
    "order-list": Access(read=ORDERS_READ, write=ORDERS_WRITE),
    "order-detail": Access(read=ORDERS_READ),
    "order-cancel": Access(write=ORDERS_WRITE),
    "order-priority": Access(write=ORDERS_WRITE),
    "vehicle-list": Access(read=VEHICLES_READ),
    "vehicle-detail": Access(read=VEHICLES_READ),
    "vehicle-commands": Access(read=VEHICLES_READ),
    "vehicle-pause": Access(write=VEHICLES_COMMAND),
    "vehicle-resume": Access(write=VEHICLES_COMMAND),
    "vehicle-instant-actions": Access(write=VEHICLES_COMMAND),
    "vehicle-charge": Access(write=CHARGE_OR_PARK),
    "vehicle-park": Access(write=CHARGE_OR_PARK),
    "webhook-list": Access(read=WEBHOOKS, write=WEBHOOKS),
    "webhook-detail": Access(read=WEBHOOKS, write=WEBHOOKS),
    "webhook-ping": Access(write=WEBHOOKS),
    "load-location": Access(read=scope("loads:read")),
    "load-move": Access(write=scope("loads:write")),
    "lif-import": Access(write=LAYOUTS_WRITE),
    "map-list": Access(read=LAYOUTS_READ),
    "map-detail": Access(read=LAYOUTS_READ),
    "map-layout": Access(read=LAYOUTS_READ),
    "map-lif": Access(read=LAYOUTS_READ),
    "map-speed-limits": Access(read=LAYOUTS_READ),
    "map-validation": Access(read=LAYOUTS_READ),
    "maprelease-list": Access(read=LAYOUTS_READ, write=LAYOUTS_WRITE),
    "maprelease-detail": Access(read=LAYOUTS_READ),
    "maprelease-distribute": Access(write=LAYOUTS_WRITE),
    "site-list": Access(read=LAYOUTS_READ),
    "site-detail": Access(read=LAYOUTS_READ),
    "site-lif": Access(read=LAYOUTS_READ),
    "station-list": Access(read=LAYOUTS_READ),
    "station-detail": Access(read=LAYOUTS_READ),
    "zone-list": Access(read=LAYOUTS_READ, write=LAYOUTS_WRITE),
    "zone-detail": Access(read=LAYOUTS_READ, write=LAYOUTS_WRITE),
    "battery-vehicles": Access(read=scope("battery:read")),
    "battery-history": Access(read=scope("battery:read")),
    "battery-chargers": Access(read=scope("battery:read")),
    "battery-sessions": Access(read=scope("battery:read")),
    "maintenance-plans": Access(read=scope("maintenance:read")),
    "maintenance-work-orders": Access(read=scope("maintenance:read")),
    "maintenance-vehicles": Access(read=scope("maintenance:read")),
    "maintenance-history": Access(read=scope("maintenance:read")),
    "maintenance-errors": Access(read=scope("maintenance:read")),
}

# The schema and its two viewers: any signed-in user or client (SPECTACULAR SERVE_PERMISSIONS).
DOCUMENTATION = frozenset({"api-schema", "api-docs", "api-redoc"})


def rule_for(url_name: str | None, method: str) -> Rule | None:
    """The rule of a call, None when the endpoint or that kind of call is not listed."""
    access = ENDPOINTS.get(url_name or "")
    return access.rule(method) if access is not None else None


class ScopedAccess(BasePermission):
    """The default permission of the API: a token needs the endpoint's scope, a signed-in user
    (session or basic auth) the matching permission of their role. Unlisted: refused."""

    message = "Your token's scopes or your role do not allow this call."

    def has_permission(self, request: Request, view: Any) -> bool:
        user = request.user
        if not (user and user.is_authenticated and user.is_active):
            return False
        match = request.resolver_match
        rule = rule_for(match.url_name if match else None, request.method or "GET")
        if rule is None:
            # A method the endpoint does not have: let DRF answer 405 (nothing runs).
            return (request.method or "").upper() not in view.allowed_methods
        if request.auth is not None:  # an integration client's token (orders.models.ApiToken)
            return rule.scope in getattr(request.auth, "scopes", ())
        return rule.permission is not None and bool(user.has_perm(rule.permission))
