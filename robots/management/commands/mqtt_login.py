"""`manage.py mqtt_login MANUFACTURER SERIAL`: issue (or rotate) a vehicle's broker login."""

from typing import Any

from django.core.management.base import BaseCommand, CommandError, CommandParser

from robots.models import Vehicle
from robots.services import issue_mqtt_password


class Command(BaseCommand):
    help = (
        "Issue a new MQTT password for a registered vehicle and print it once (only its hash is "
        "kept). Then run mosquitto_config again and reload the broker."
    )

    def add_arguments(self, parser: CommandParser) -> None:
        parser.add_argument("manufacturer")
        parser.add_argument("serial_number")
        parser.add_argument("--username", default="", help="default: manufacturer_serial")

    def handle(self, *args: Any, **options: Any) -> None:
        try:
            vehicle = Vehicle.objects.get(
                manufacturer=options["manufacturer"], serial_number=options["serial_number"]
            )
        except Vehicle.DoesNotExist:
            raise CommandError(
                f"no vehicle {options['manufacturer']}/{options['serial_number']} is registered"
            ) from None
        try:
            username, password = issue_mqtt_password(vehicle=vehicle, username=options["username"])
        except ValueError as error:
            raise CommandError(str(error)) from error
        self.stdout.write(f"user: {username}\npassword: {password}")
