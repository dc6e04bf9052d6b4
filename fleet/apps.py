"""App config for the project package (templates tags, management commands, the audit trail)."""

from typing import Any

from django.apps import AppConfig
from django.db.models.signals import post_save


class FleetConfig(AppConfig):
    name = "fleet"
    verbose_name = "Fleet"

    def ready(self) -> None:
        from django.contrib.admin.models import LogEntry

        post_save.connect(_audit_admin_change, sender=LogEntry, dispatch_uid="audit-admin-log")


def _audit_admin_change(sender: Any, instance: Any, created: bool, **kwargs: Any) -> None:
    """Every add, change and delete made in the admin goes into the audit trail as well."""
    if not created:
        return
    from fleet.audit import record

    verb = {1: "add", 2: "change", 3: "delete"}.get(instance.action_flag, "change")
    record(
        f"admin.{verb}",
        target_type=instance.content_type.model if instance.content_type else "",
        target_id=instance.object_id or "",
        detail={"object": instance.object_repr, "message": instance.get_change_message()},
    )
