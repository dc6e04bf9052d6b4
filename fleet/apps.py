"""App config for the project package (templates tags, management commands, the audit trail)."""

from typing import Any

from django.apps import AppConfig
from django.db.models.signals import post_migrate, post_save


class FleetConfig(AppConfig):
    name = "fleet"
    verbose_name = "Fleet"

    def ready(self) -> None:
        from django.contrib.admin.models import LogEntry

        post_save.connect(_audit_admin_change, sender=LogEntry, dispatch_uid="audit-admin-log")
        post_migrate.connect(_sync_roles_after_migrate, dispatch_uid="fleet-sync-roles")


def _sync_roles_after_migrate(sender: AppConfig, using: str = "default", **kwargs: Any) -> None:
    """Keep the role groups in step after a migrate (and a test database flush). Runs once, for
    the last app with models: by then every app's permissions exist."""
    from django.apps import apps

    with_models = [config for config in apps.get_app_configs() if config.models_module is not None]
    if not with_models or sender is not with_models[-1]:
        return
    from fleet.roles import sync_roles

    sync_roles(using=using)


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
