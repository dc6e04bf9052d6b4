"""`manage.py create_user NAME --role operator`: a person who works in the fleet pages."""

import getpass
from typing import Any

from django.contrib.auth import get_user_model
from django.core.management.base import BaseCommand, CommandError, CommandParser

from fleet.roles import ROLES, assign_role


class Command(BaseCommand):
    help = "Create a user with one role, or give an existing user that role."

    def add_arguments(self, parser: CommandParser) -> None:
        parser.add_argument("username")
        parser.add_argument("--role", required=True, choices=ROLES)
        parser.add_argument("--email", default="")
        parser.add_argument(
            "--password", help="the password (asked for when left out and the user is new)"
        )

    def handle(self, *args: Any, **options: Any) -> None:
        users = get_user_model().objects
        user, created = users.get_or_create(
            username=options["username"], defaults={"email": options["email"]}
        )
        password = options["password"]
        if created and password is None:
            password = getpass.getpass(f"Password for {user.username}: ")
            if not password:
                user.delete()
                raise CommandError("a new user needs a password")
        if password is not None:
            user.set_password(password)
            user.save(update_fields=["password"])
        assign_role(user=user, role=options["role"])
        verb = "created" if created else "updated"
        self.stdout.write(f"{user.username} {verb} with the role {options['role']}")
