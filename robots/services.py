"""Writes of the vehicle registry. The live snapshot is written in batches by `control`."""

import re
import secrets
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from django.db import connection, transaction
from django.utils import timezone

from fleet.bulk import update_rows
from robots import mosquitto
from robots.models import MqttCredential, Vehicle

SNAPSHOT_FIELDS = [
    "connection",
    "protocol_version",
    "interface_name",
    "map_id",
    "x",
    "y",
    "theta",
    "position_initialized",
    "battery_charge",
    "charging",
    "driving",
    "paused",
    "operating_mode",
    "errors",
    "loads",
    "order_id",
    "order_update_id",
    "last_node_id",
    "last_node_sequence_id",
    "last_seen",
    "clock_skew",
    "protocol_counters",
]


def register_vehicles(*, identities: Iterable[tuple[str, str]]) -> dict[tuple[str, str], int]:
    """Create registry rows for vehicles seen for the first time; return the ids of all of them.

    Idempotent and race-free: a row another process created first is simply reused.
    """
    wanted = set(identities)
    if not wanted:
        return {}
    Vehicle.objects.bulk_create(
        [Vehicle(manufacturer=m, serial_number=s) for m, s in wanted], ignore_conflicts=True
    )
    found: dict[tuple[str, str], int] = {}
    for manufacturer in {m for m, _ in wanted}:
        serials = [s for m, s in wanted if m == manufacturer]
        for pk, serial in Vehicle.objects.filter(
            manufacturer=manufacturer, serial_number__in=serials
        ).values_list("pk", "serial_number"):
            found[(manufacturer, serial)] = pk
    return found


@transaction.atomic
def save_snapshots(*, snapshots: Sequence[dict[str, Any]]) -> int:
    """Write live snapshots (dicts with `pk` and SNAPSHOT_FIELDS) in one bulk update. Other keys
    (e.g. `loads_known`) are for the flush's observers and are not stored; a field a snapshot
    lacks is written as the field's default (as a `Vehicle` built from the snapshot has it)."""
    if not snapshots:
        return 0
    if connection.vendor == "postgresql":
        return _update_from_values(snapshots)
    vehicles = [
        Vehicle(pk=snapshot["pk"], **{f: snapshot[f] for f in SNAPSHOT_FIELDS if f in snapshot})
        for snapshot in snapshots
    ]
    return Vehicle.objects.bulk_update(vehicles, SNAPSHOT_FIELDS, batch_size=500)


def _update_from_values(snapshots: Sequence[dict[str, Any]]) -> int:
    """The same rows as `bulk_update`, in one statement (`fleet.bulk`): `bulk_update` cost
    about 0.5 ms of CPU per vehicle in `control`'s flush (docs/LOAD.md). The rows are made
    from the snapshots directly: building a `Vehicle` per row first was 40 % of the flush;
    a field a snapshot lacks is written as its default."""
    rows = [
        {"pk": snapshot["pk"]}
        | {name: snapshot[name] if name in snapshot else _default(name) for name in SNAPSHOT_FIELDS}
        for snapshot in snapshots
    ]
    return update_rows(Vehicle, rows, SNAPSHOT_FIELDS)


def _default(name: str) -> Any:
    return Vehicle._meta.get_field(name).get_default()  # type: ignore[union-attr]


def save_factsheets(*, factsheets: dict[int, dict[str, Any]]) -> None:
    """Store the latest factsheet of each vehicle (they change rarely, so one update each)."""
    for pk, factsheet in factsheets.items():
        Vehicle.objects.filter(pk=pk).update(factsheet=factsheet)


def default_mqtt_username(vehicle: Vehicle) -> str:
    """`manufacturer_serial`, reduced to characters every broker accepts in a user name."""
    return re.sub(r"[^A-Za-z0-9_.-]", "_", f"{vehicle.manufacturer}_{vehicle.serial_number}")


@transaction.atomic
def issue_mqtt_password(*, vehicle: Vehicle, username: str = "") -> tuple[str, str]:
    """Give the vehicle a new random broker password; return (user name, password).

    The password is returned once and only its hash is kept, so issuing again rotates it. The
    broker learns it when `write_broker_files` runs again.
    """
    name = mosquitto.check_login_name(username or default_mqtt_username(vehicle))
    if MqttCredential.objects.filter(username=name).exclude(vehicle=vehicle).exists():
        raise ValueError(f"MQTT user name {name!r} already belongs to another vehicle")
    password = secrets.token_urlsafe(24)
    MqttCredential.objects.update_or_create(
        vehicle=vehicle,
        defaults={
            "username": name,
            "password_hash": mosquitto.hash_password(password),
            "enabled": True,
            "issued_at": timezone.now(),
        },
    )
    return name, password


@dataclass(frozen=True)
class BrokerFiles:
    """The three files `write_broker_files` wrote and how many vehicle logins they hold."""

    config: Path
    passwords: Path
    acl: Path
    vehicles: int


def write_broker_files(
    *,
    directory: Path,
    master_username: str,
    master_password: str,
    listeners: mosquitto.Listeners,
) -> BrokerFiles:
    """Write mosquitto.conf, the password file and the ACL file for every enabled vehicle login.

    Vehicles without a login are left out: they cannot connect until one is issued.
    """
    logins = [
        mosquitto.VehicleLogin(
            username=credential.username,
            password_hash=credential.password_hash,
            interface=credential.vehicle.interface_name,
            protocol_version=credential.vehicle.protocol_version,
            manufacturer=credential.vehicle.manufacturer,
            serial_number=credential.vehicle.serial_number,
        )
        for credential in MqttCredential.objects.filter(enabled=True).select_related("vehicle")
    ]
    interfaces = {login.interface for login in logins} or {"uagv"}
    interfaces |= set(Vehicle.objects.values_list("interface_name", flat=True))
    master = mosquitto.MasterLogin(
        username=master_username,
        password_hash=mosquitto.hash_password(master_password),
        interfaces=tuple(sorted(interfaces)),
    )
    directory.mkdir(parents=True, exist_ok=True)
    files = BrokerFiles(
        config=directory / "mosquitto.conf",
        passwords=directory / "passwd",
        acl=directory / "acl",
        vehicles=len(logins),
    )
    files.passwords.write_text(mosquitto.render_passwords(master, logins))
    files.passwords.chmod(0o600)
    files.acl.write_text(mosquitto.render_acl(master, logins))
    files.config.write_text(
        mosquitto.render_config(
            listeners,
            password_file=str(files.passwords.resolve()),
            acl_file=str(files.acl.resolve()),
        )
    )
    return files
