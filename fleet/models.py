"""The audit trail (every change and every command, who gave it, when and from where) and the
carrier of the fleet-wide permissions."""

from typing import Any

from django.conf import settings
from django.db import models

from fleet.roles import FLEET_CAPABILITIES


class AuditEntry(models.Model):
    """One recorded change or command. Append-only: never edited or deleted from the UI.

    `actor` is the user name, `client:<name>` for an integration client (its user), or
    `system:<process>` for control, dispatch and other automatic work; `source` is the client
    address or the process.
    """

    at = models.DateTimeField(auto_now_add=True, db_index=True)
    actor = models.CharField(max_length=150, db_index=True)
    user = models.ForeignKey(
        settings.AUTH_USER_MODEL, null=True, blank=True, on_delete=models.SET_NULL, related_name="+"
    )
    source = models.CharField(max_length=100, blank=True, help_text="address or process")
    action = models.CharField(max_length=100, db_index=True, help_text="e.g. order.cancel")
    target_type = models.CharField(max_length=50, blank=True)
    target_id = models.CharField(max_length=100, blank=True, db_index=True)
    detail = models.JSONField(default=dict, blank=True)

    class Meta:
        ordering = ["-at", "-pk"]
        verbose_name_plural = "audit entries"

    def __str__(self) -> str:
        target = f"{self.target_type} {self.target_id}".strip()
        return f"{self.at:%Y-%m-%d %H:%M:%S} {self.actor} {self.action} {target}"

    def save(self, *args: Any, **kwargs: Any) -> None:
        if self.pk is not None:
            raise ValueError("audit entries are never changed")
        super().save(*args, **kwargs)

    def delete(self, *args: Any, **kwargs: Any) -> tuple[int, dict[str, int]]:
        raise ValueError("audit entries are never deleted")


class FleetPermission(models.Model):
    """Carries the fleet-wide capabilities (`fleet.roles.FLEET_CAPABILITIES`) as Django
    permissions (`fleet.view_operations`, ...). No table: only its content type and permissions
    exist, so groups (the roles) and users can hold them like any model permission."""

    class Meta:
        managed = False
        default_permissions = ()
        permissions = FLEET_CAPABILITIES

    def __str__(self) -> str:
        return "fleet permission"
