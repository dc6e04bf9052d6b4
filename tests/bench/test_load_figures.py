"""Pure parts of the load benchmark's report (no processes)."""

from pathlib import Path

from bench.load.run import dropping_clients


def test_the_clients_mosquitto_dropped_messages_for_are_named_once_each(tmp_path: Path) -> None:
    log = tmp_path / "mosquitto.log"
    log.write_text(
        "1692604552: New connection from 127.0.0.1:33904 on port 1883.\n"
        "1692604552: Outgoing messages are being dropped for client raw-probe.\n"
        "1692604553: Outgoing messages are being dropped for client P1-17.\n"
        "1692604559: Outgoing messages are being dropped for client raw-probe.\n"
    )

    assert dropping_clients(log) == ["P1-17", "raw-probe"]
    assert dropping_clients(tmp_path / "missing.log") == []
