"""`manage.py mosquitto_config --out DIR`: the broker's configuration, password file and ACL."""

from pathlib import Path
from typing import Any

from django.conf import settings
from django.core.management.base import BaseCommand, CommandError, CommandParser

from fleet.mqtt import BrokerAddress
from robots import mosquitto
from robots.services import write_broker_files


class Command(BaseCommand):
    help = (
        "Write mosquitto.conf, a password file and an ACL file into --out: every vehicle with an "
        "MQTT login may publish only its own reports and read only its own commands; the fleet "
        "manager logs in with the user and password of MQTT_URL. Run again after issuing logins."
    )

    def add_arguments(self, parser: CommandParser) -> None:
        parser.add_argument("--out", required=True, type=Path, help="directory to write into")
        parser.add_argument("--port", type=int, default=1883, help="plain listener port")
        parser.add_argument("--bind", default="", help="address to bind (default: all)")
        parser.add_argument("--tls-port", type=int, help="add a TLS listener on this port")
        parser.add_argument("--cafile", default="", help="CA certificate for the TLS listener")
        parser.add_argument("--certfile", default="", help="server certificate (TLS)")
        parser.add_argument("--keyfile", default="", help="server private key (TLS)")
        parser.add_argument(
            "--extra", action="append", default=[], help="a further mosquitto.conf line"
        )

    def handle(self, *args: Any, **options: Any) -> None:
        address = BrokerAddress.from_url(settings.MQTT_URL)
        if not (address.username and address.password):
            raise CommandError(
                "MQTT_URL must carry the fleet manager's login, e.g. "
                "mqtt://fleet:SECRET@broker:1883, so that control can connect after the change"
            )
        try:
            listeners = mosquitto.Listeners(
                port=options["port"],
                bind=options["bind"],
                tls_port=options["tls_port"],
                cafile=options["cafile"],
                certfile=options["certfile"],
                keyfile=options["keyfile"],
                extra=options["extra"],
            )
            files = write_broker_files(
                directory=options["out"],
                master_username=address.username,
                master_password=address.password,
                listeners=listeners,
            )
        except ValueError as error:
            raise CommandError(str(error)) from error
        self.stdout.write(
            f"wrote {files.config}, {files.passwords} and {files.acl} "
            f"({files.vehicles} vehicle logins); start with: mosquitto -c {files.config}"
        )
