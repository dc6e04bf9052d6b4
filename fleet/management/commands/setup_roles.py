"""`manage.py setup_roles`: create or update the role groups (also done after every migrate)."""

from typing import Any

from django.core.management.base import BaseCommand

from fleet.roles import sync_roles


class Command(BaseCommand):
    help = "Create or update one group per role (operator, technician, manager, administrator)."

    def handle(self, *args: Any, **options: Any) -> None:
        for role, count in sync_roles().items():
            self.stdout.write(f"{role}: {count} permissions")
