"""The vehicle registry: identity, protocol, factsheet, connection and the live state snapshot."""

from django.db import models


class Vehicle(models.Model):
    """A VDA 5050 vehicle, known by manufacturer + serial number.

    The snapshot fields mirror the vehicle's latest `state` as `control` last flushed it (at most
    about a second old); `control` owns them and writes them in batches. Everything else is
    registry data that staff may edit.
    """

    class Connection(models.TextChoices):
        UNKNOWN = "UNKNOWN", "unknown"
        ONLINE = "ONLINE", "online"
        # Says ONLINE (or said nothing) but sent no state within its state interval.
        UNREACHABLE = "UNREACHABLE", "unreachable"
        OFFLINE = "OFFLINE", "offline"
        CONNECTIONBROKEN = "CONNECTIONBROKEN", "connection broken"

    manufacturer = models.CharField(max_length=100)
    serial_number = models.CharField(max_length=100)
    name = models.CharField(max_length=100, blank=True)
    interface_name = models.CharField(max_length=100, default="uagv")
    protocol_version = models.CharField(max_length=20, default="2.0.0")

    class Dialect(models.TextChoices):
        """Known field deviations of deployed vehicle stacks (docs/DIALECTS.md)."""

        STANDARD = "STANDARD", "standard (as the schemas say)"
        INSTANT_ACTIONS_KEY = (
            "INSTANT_ACTIONS_KEY",
            ("early 2.0 stacks: instant actions under `instantActions` instead of `actions`"),
        )

    dialect = models.CharField(
        max_length=30,
        choices=Dialect.choices,
        default=Dialect.STANDARD,
        help_text="what control sends to this vehicle; takes effect within 10 s",
    )
    factsheet = models.JSONField(null=True, blank=True)
    connection = models.CharField(
        max_length=20, choices=Connection.choices, default=Connection.UNKNOWN
    )
    # Live snapshot (owned by control).
    map_id = models.CharField(max_length=100, blank=True)
    x = models.FloatField(null=True, blank=True)
    y = models.FloatField(null=True, blank=True)
    theta = models.FloatField(null=True, blank=True)
    position_initialized = models.BooleanField(default=False)
    battery_charge = models.FloatField(null=True, blank=True, help_text="percent")
    charging = models.BooleanField(default=False)
    driving = models.BooleanField(default=False)
    paused = models.BooleanField(default=False)
    operating_mode = models.CharField(max_length=20, blank=True)
    errors = models.JSONField(default=list, blank=True)
    loads = models.JSONField(default=list, blank=True)
    order_id = models.CharField(max_length=100, blank=True)
    order_update_id = models.PositiveIntegerField(null=True, blank=True)
    last_node_id = models.CharField(max_length=100, blank=True)
    last_node_sequence_id = models.PositiveIntegerField(null=True, blank=True)
    last_seen = models.DateTimeField(null=True, blank=True)
    clock_skew = models.FloatField(
        null=True, blank=True, help_text="seconds the vehicle's clock is behind ours (display only)"
    )
    protocol_counters = models.JSONField(
        default=dict, blank=True, help_text="dropped duplicates, stale and malformed messages, gaps"
    )
    created_at = models.DateTimeField(auto_now_add=True)
    updated_at = models.DateTimeField(auto_now=True)

    class Meta:
        ordering = ["manufacturer", "serial_number"]
        constraints = [
            models.UniqueConstraint(
                fields=["manufacturer", "serial_number"], name="vehicle_identity_unique"
            ),
        ]

    def __str__(self) -> str:
        return self.name or f"{self.manufacturer}/{self.serial_number}"

    @property
    def has_fatal_error(self) -> bool:
        return any(e.get("errorLevel") == "FATAL" for e in self.errors or [])

    @property
    def is_available(self) -> bool:
        """Whether dispatch may give this vehicle work (connection, mode, errors, position)."""
        return (
            self.connection == self.Connection.ONLINE
            and self.operating_mode in {"AUTOMATIC", "SEMIAUTOMATIC"}
            and not self.has_fatal_error
            and not self.paused
            and bool(self.last_node_id)
        )


class MqttCredential(models.Model):
    """A vehicle's own login at the MQTT broker.

    Only the hash in Mosquitto's password-file format is stored; the password is shown once when
    issued. The generated ACL confines the login to the vehicle's own topics
    (`manage.py mosquitto_config`).
    """

    vehicle = models.OneToOneField(
        Vehicle, on_delete=models.CASCADE, related_name="mqtt_credential"
    )
    username = models.CharField(max_length=100, unique=True)
    password_hash = models.CharField(max_length=200)
    enabled = models.BooleanField(
        default=True, help_text="disabled logins are left out of the broker's files"
    )
    issued_at = models.DateTimeField()

    class Meta:
        ordering = ["username"]

    def __str__(self) -> str:
        return self.username
