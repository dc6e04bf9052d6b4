"""Mosquitto's password file, ACL file and configuration, rendered from plain values.

Every vehicle gets its own login and may publish only its own vehicle→master topics (state,
connection, factsheet, visualization) and read only its own master→vehicle topics (order,
instantActions; 3.0 adds zoneSet and responses). The fleet manager reads all vehicle→master topics
and writes all master→vehicle topics of the interfaces in use. Nothing else is granted, so nothing
crosses between vehicles (tests/robots/test_mosquitto_acl.py checks every pair against a real
broker).

Pure functions only: the services in `robots.services` gather the values and write the files.
"""

import base64
import hashlib
import os
from dataclasses import dataclass, field

# Mosquitto 2's "$7$" scheme: PBKDF2-HMAC-SHA512, 12-byte salt, 64-byte key (mosquitto_passwd).
PBKDF2_ITERATIONS = 101
SALT_BYTES = 12

VEHICLE_TO_MASTER = ("state", "connection", "factsheet", "visualization")
MASTER_TO_VEHICLE = {"v1": ("order", "instantActions"), "v2": ("order", "instantActions")}
MASTER_TO_VEHICLE_3 = ("order", "instantActions", "zoneSet", "responses")


def hash_password(password: str, *, salt: bytes | None = None) -> str:
    """The line Mosquitto's password file holds for `password` (after `username:`)."""
    salt = os.urandom(SALT_BYTES) if salt is None else salt
    key = hashlib.pbkdf2_hmac("sha512", password.encode(), salt, PBKDF2_ITERATIONS)
    encoded_salt = base64.b64encode(salt).decode()
    return f"$7${PBKDF2_ITERATIONS}${encoded_salt}${base64.b64encode(key).decode()}"


def major_version(protocol_version: str) -> str:
    """The topic level for a protocol version: "2.1.0" → "v2"."""
    return "v" + (protocol_version.split(".", 1)[0] or "2")


def master_to_vehicle_topics(major: str) -> tuple[str, ...]:
    """What the master sends to a vehicle of this major version."""
    return MASTER_TO_VEHICLE.get(major, MASTER_TO_VEHICLE_3)


def check_login_name(name: str) -> str:
    """Refuse names the password or ACL file cannot hold (they are line- and space-separated)."""
    if not name or any(c.isspace() or c in ":#" for c in name):
        raise ValueError(f"MQTT user name {name!r} may not be empty or contain spaces, ':' or '#'")
    return name


def check_topic_level(level: str) -> str:
    """Refuse topic levels with MQTT wildcards or separators (they would widen a grant)."""
    if not level or any(c in "+#/" or c.isspace() for c in level):
        raise ValueError(
            f"topic level {level!r} may not be empty or contain '+', '#', '/' or spaces"
        )
    return level


@dataclass(frozen=True)
class VehicleLogin:
    """One vehicle's broker login and the topic prefix it is confined to."""

    username: str
    password_hash: str
    interface: str
    protocol_version: str
    manufacturer: str
    serial_number: str

    @property
    def prefix(self) -> str:
        levels = (self.interface, major_version(self.protocol_version))
        identity = (self.manufacturer, self.serial_number)
        return "/".join(check_topic_level(level) for level in (*levels, *identity))

    def rules(self) -> list[str]:
        """ACL lines: write its own reports, read its own commands, nothing else."""
        major = major_version(self.protocol_version)
        lines = [f"user {check_login_name(self.username)}"]
        lines += [f"topic write {self.prefix}/{topic}" for topic in VEHICLE_TO_MASTER]
        lines += [f"topic read {self.prefix}/{topic}" for topic in master_to_vehicle_topics(major)]
        return lines


@dataclass(frozen=True)
class MasterLogin:
    """The fleet manager's broker login: all vehicles' reports in, all commands out."""

    username: str
    password_hash: str
    interfaces: tuple[str, ...] = ("uagv",)

    def rules(self) -> list[str]:
        lines = [f"user {check_login_name(self.username)}"]
        for interface in sorted(set(self.interfaces)):
            base = f"{check_topic_level(interface)}/+/+/+"
            lines += [f"topic read {base}/{topic}" for topic in VEHICLE_TO_MASTER]
            lines += [f"topic write {base}/{topic}" for topic in MASTER_TO_VEHICLE_3]
        return lines


@dataclass(frozen=True)
class Listeners:
    """Where the broker listens; a TLS listener is added when certificate paths are given."""

    port: int = 1883
    bind: str = ""
    tls_port: int | None = None
    cafile: str = ""
    certfile: str = ""
    keyfile: str = ""
    extra: list[str] = field(default_factory=list)

    def __post_init__(self) -> None:
        if self.tls_port is not None and not (self.certfile and self.keyfile):
            raise ValueError("a TLS listener needs both a certificate file and a key file")


def render_passwords(master: MasterLogin, vehicles: list[VehicleLogin]) -> str:
    names = [master.username, *(v.username for v in vehicles)]
    duplicates = sorted({n for n in names if names.count(n) > 1})
    if duplicates:
        raise ValueError(f"MQTT user names used twice: {', '.join(duplicates)}")
    logins = [(master.username, master.password_hash)]
    logins += [(v.username, v.password_hash) for v in vehicles]
    return "".join(f"{check_login_name(name)}:{hashed}\n" for name, hashed in logins)


def render_acl(master: MasterLogin, vehicles: list[VehicleLogin]) -> str:
    blocks = [master.rules(), *(v.rules() for v in vehicles)]
    header = "# Generated by `manage.py mosquitto_config`; edits are overwritten.\n"
    return header + "\n".join("\n".join(block) + "\n" for block in blocks)


MAX_QUEUED_MESSAGES = 20_000


def render_config(listeners: Listeners, *, password_file: str, acl_file: str) -> str:
    """mosquitto.conf: no anonymous clients, every listener behind the password and ACL files."""
    lines = [
        "# Generated by `manage.py mosquitto_config`; edits are overwritten.",
        "per_listener_settings false",
        "allow_anonymous false",
        f"password_file {password_file}",
        f"acl_file {acl_file}",
        # Per client, beyond it messages to a slow client are dropped. Only control subscribes
        # to the whole fleet: ~10 s of 1,000 vehicles' state + visualization rides out a stall
        # (1,000 lost control's messages in the load runs, docs/LOAD.md). Bounded memory.
        f"max_queued_messages {MAX_QUEUED_MESSAGES}",
        f"listener {listeners.port} {listeners.bind}".rstrip(),
        "protocol mqtt",
    ]
    if listeners.tls_port is not None:
        lines += [f"listener {listeners.tls_port} {listeners.bind}".rstrip(), "protocol mqtt"]
        if listeners.cafile:
            lines.append(f"cafile {listeners.cafile}")
        lines += [
            f"certfile {listeners.certfile}",
            f"keyfile {listeners.keyfile}",
            "tls_version tlsv1.2",
        ]
    return "\n".join([*lines, *listeners.extra]) + "\n"
