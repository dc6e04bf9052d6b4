"""The fleet's roles and the permissions each one holds.

A role is a Django group of the same name, kept in step with `ROLE_PERMISSIONS` by
`sync_roles()` (run after every migrate and by `manage.py setup_roles`). Views, admin, the API
and websockets check *permissions*, never role names, so a site can give a person a single extra
permission without inventing a role.

The fleet-wide capabilities are custom permissions on `fleet.FleetPermission`; the pages check
those. Per-model permissions (`ROLE_MODEL_PERMISSIONS`) decide what a role sees and changes in
the admin. API scopes of integration clients (`API_SCOPES`) map onto the same permissions for
signed-in users. docs/SECURITY.md has the tables.
"""

from __future__ import annotations

from typing import Any

# Fleet-wide capabilities (codenames on fleet.FleetPermission).
VIEW_OPERATIONS = "fleet.view_operations"  # live map, vehicles, orders board, alerts (read)
OPERATE_ORDERS = "fleet.operate_orders"  # create, cancel, reprioritise, reassign orders
COMMAND_VEHICLES = "fleet.command_vehicles"  # instant actions: pause, resume, cancel, init position
SEND_TO_CHARGE_OR_PARK = "fleet.send_to_charge_or_park"  # charge/park moves of a vehicle
ACKNOWLEDGE_ALERTS = "fleet.acknowledge_alerts"  # acknowledge and resolve alerts
MAINTAIN_VEHICLES = "fleet.maintain_vehicles"  # work orders, out of service and back
VIEW_REPORTS = "fleet.view_reports"  # manager reports and CSV exports
VIEW_AUDIT = "fleet.view_auditentry"  # the audit trail (model permission of AuditEntry)
MANAGE_LAYOUTS = "fleet.manage_layouts"  # layouts, zones, stations, map releases
ADMINISTER = "fleet.administer"  # vehicles registry, MQTT logins, users, clients, settings

FLEET_CAPABILITIES: tuple[tuple[str, str], ...] = (
    ("view_operations", "See live operations: map, vehicles, orders, alerts"),
    ("operate_orders", "Create, cancel, reprioritise and reassign transport orders"),
    ("command_vehicles", "Send instant actions to vehicles"),
    ("send_to_charge_or_park", "Send vehicles to charge or to park"),
    ("acknowledge_alerts", "Acknowledge and resolve alerts"),
    ("maintain_vehicles", "Manage work orders and take vehicles out of service"),
    ("view_reports", "Read manager reports and export them"),
    ("manage_layouts", "Edit layouts, zones and stations; release maps"),
    ("administer", "Manage vehicles, MQTT logins, users, integration clients and settings"),
)

OPERATOR = "operator"
TECHNICIAN = "technician"
MANAGER = "manager"
ADMINISTRATOR = "administrator"
ROLES = (OPERATOR, TECHNICIAN, MANAGER, ADMINISTRATOR)

ROLE_PERMISSIONS: dict[str, frozenset[str]] = {
    OPERATOR: frozenset(
        {
            VIEW_OPERATIONS,
            OPERATE_ORDERS,
            COMMAND_VEHICLES,
            SEND_TO_CHARGE_OR_PARK,
            ACKNOWLEDGE_ALERTS,
        }
    ),
    TECHNICIAN: frozenset(
        {
            VIEW_OPERATIONS,
            COMMAND_VEHICLES,
            SEND_TO_CHARGE_OR_PARK,
            ACKNOWLEDGE_ALERTS,
            MAINTAIN_VEHICLES,
        }
    ),
    MANAGER: frozenset({VIEW_OPERATIONS, VIEW_REPORTS, VIEW_AUDIT}),
    # Administrators hold every permission of the project (sync_roles adds the model ones).
    ADMINISTRATOR: frozenset(
        {
            VIEW_OPERATIONS,
            OPERATE_ORDERS,
            COMMAND_VEHICLES,
            SEND_TO_CHARGE_OR_PARK,
            ACKNOWLEDGE_ALERTS,
            MAINTAIN_VEHICLES,
            VIEW_REPORTS,
            VIEW_AUDIT,
            MANAGE_LAYOUTS,
            ADMINISTER,
        }
    ),
}

# Model permissions a role holds in the admin, as "app_label.model" (or "app_label.*") → actions.
# Technicians keep the maintenance records; managers read operations records (never secrets:
# integration clients, tokens, webhook subscriptions and MQTT logins stay with administrators).
_READ = ("view",)
ROLE_MODEL_PERMISSIONS: dict[str, dict[str, tuple[str, ...]]] = {
    OPERATOR: {},
    TECHNICIAN: {
        "maintenance.*": ("view", "add", "change"),
        "robots.vehicle": _READ,
        "alerts.alert": _READ,
        "battery.*": _READ,
    },
    MANAGER: {
        "orders.transportorder": _READ,
        "orders.orderstep": _READ,
        "orders.orderevent": _READ,
        "orders.ordersequence": _READ,
        "orders.vehiclecommand": _READ,
        "orders.recurringorder": _READ,
        "robots.vehicle": _READ,
        "alerts.*": _READ,
        "battery.*": _READ,
        "maintenance.*": _READ,
        "inventory.*": _READ,
        "reports.*": _READ,
    },
    ADMINISTRATOR: {},  # every permission of the project, see sync_roles
}

# Who may enter the admin at all (besides superusers): staff users holding one of these.
ADMIN_ENTRY_PERMISSIONS = (ADMINISTER, MAINTAIN_VEHICLES, VIEW_REPORTS)
# Roles whose users are staff (may sign in to the admin); operators work in the pages only.
STAFF_ROLES = frozenset({TECHNICIAN, MANAGER, ADMINISTRATOR})

# API scopes of integration clients: scope → (what it allows, the permission a signed-in user
# needs for the same endpoints; None: clients only). fleet.api_access maps every API endpoint
# to a scope.
API_SCOPES: dict[str, tuple[str, str | None]] = {
    "orders:read": ("Read transport orders", VIEW_OPERATIONS),
    "orders:write": ("Create, cancel and reprioritise transport orders", OPERATE_ORDERS),
    "vehicles:read": ("Read vehicles and their commands", VIEW_OPERATIONS),
    "vehicles:command": ("Pause, resume, charge, park vehicles; instant actions", COMMAND_VEHICLES),
    "loads:read": ("Where a load is", VIEW_OPERATIONS),
    "loads:write": ("Move a load (creates a transport order)", OPERATE_ORDERS),
    "layouts:read": ("Read maps, sites, stations, zones and map releases", VIEW_OPERATIONS),
    "layouts:write": ("Import LIF, change zones, release and distribute maps", MANAGE_LAYOUTS),
    "maintenance:read": ("Read service plans, work orders, counters and errors", VIEW_OPERATIONS),
    "battery:read": ("Read batteries, chargers and charge sessions", VIEW_OPERATIONS),
    # Subscriptions belong to a client: no signed-in user manages them through the API.
    "webhooks:manage": ("Manage the client's own webhook subscriptions", None),
}
ALL_API_SCOPES: tuple[str, ...] = tuple(API_SCOPES)


def _model_permissions(patterns: dict[str, tuple[str, ...]], using: str) -> list[Any]:
    from django.contrib.auth.models import Permission

    found: list[Any] = []
    for pattern, actions in patterns.items():
        app_label, model = pattern.split(".")
        permissions = Permission.objects.using(using).filter(
            content_type__app_label=app_label,
            codename__in=[f"{action}_{m}" for action in actions for m in _models(app_label, model)],
        )
        found.extend(permissions)
    return found


def _models(app_label: str, model: str) -> list[str]:
    from django.apps import apps

    if model != "*":
        return [model]
    return [m._meta.model_name or "" for m in apps.get_app_config(app_label).get_models()]


def sync_roles(using: str = "default") -> dict[str, int]:
    """Create or update one group per role with exactly its permissions; returns how many
    permissions each holds. Idempotent: run after every migrate and by `manage.py setup_roles`.
    Administrators get every permission of the project."""
    from django.contrib.auth.models import Group, Permission

    counts: dict[str, int] = {}
    for role in ROLES:
        group, _ = Group.objects.using(using).get_or_create(name=role)
        if role == ADMINISTRATOR:
            permissions = list(Permission.objects.using(using).all())
        else:
            named = [_permission(name, using) for name in ROLE_PERMISSIONS[role]]
            permissions = [p for p in named if p is not None]
            permissions += _model_permissions(ROLE_MODEL_PERMISSIONS[role], using)
        group.permissions.set(permissions)
        counts[role] = len(set(permissions))
    return counts


def _permission(name: str, using: str) -> Any:
    from django.contrib.auth.models import Permission

    app_label, codename = name.split(".")
    return (
        Permission.objects.using(using)
        .filter(content_type__app_label=app_label, codename=codename)
        .first()
    )


def assign_role(*, user: Any, role: str) -> None:
    """Give `user` exactly one role (its group; other role groups are removed) and make them
    staff when the role works in the admin. Other, non-role groups stay."""
    from django.contrib.auth.models import Group

    if role not in ROLES:
        raise ValueError(f"unknown role {role!r}; one of {', '.join(ROLES)}")
    if not Group.objects.filter(name=role).exists():
        sync_roles()
    user.groups.remove(*Group.objects.filter(name__in=ROLES).exclude(name=role))
    user.groups.add(Group.objects.get(name=role))
    user.is_staff = role in STAFF_ROLES
    user.save(update_fields=["is_staff"])
