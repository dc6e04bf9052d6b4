"""Map distribution (REFERENCE K.47): releases reach 2.1/3.0 vehicles through downloadMap,
enableMap and deleteMap, followed in `state.maps`; orders wait for the released map.

Runs for 2.0.0, 2.1.0 and 3.0.0 (2.0 has no map distribution: nothing may be sent or held);
every published message is validated against its official schema (fixture `sent`).
"""

import pytest

from tests.control import fakes
from tests.control import test_controller as base
from tests.control.distribution_support import TARGET, actions, online, state
from tests.control.fakes import order, topic
from tests.control.test_controller import orders_in

# The controller tests' fixtures: once per protocol version, every message schema-checked.
protocol_version = base.protocol_version
sent = base.sent
controller = base.controller

OLD = [("demo", "1", "ENABLED")]


def with_map_distribution(version: str) -> None:
    if version == "2.0.0":
        pytest.skip("2.0 has no state.maps and no map actions")


def release(controller, target=TARGET) -> None:
    controller.distribution.set_targets({target.map_id: target}, {})


def test_K47_a_release_is_downloaded_enabled_and_the_old_version_deleted(
    controller, sent, protocol_version
) -> None:
    with_map_distribution(protocol_version)
    online(controller, maps=OLD)
    release(controller)

    ((kind, params, download_id),) = actions(sent)[-1:]
    assert kind == "downloadMap"
    assert params == {
        "mapId": "demo",
        "mapVersion": "r2",
        "mapDownloadLink": TARGET.link,
        "mapHash": TARGET.checksum,
    }
    # Still downloading: nothing new until the vehicle reports.
    controller.handle_message(
        topic(), state(header_id=2, maps=OLD, actions=((download_id, "RUNNING"),))
    )
    assert [a[0] for a in actions(sent)].count("downloadMap") == 1

    controller.handle_message(
        topic(),
        state(
            header_id=3,
            maps=[*OLD, ("demo", "r2", "DISABLED")],
            actions=((download_id, "FINISHED"),),
        ),
    )
    kind, params, enable_id = actions(sent)[-1]
    assert (kind, params) == ("enableMap", {"mapId": "demo", "mapVersion": "r2"})

    controller.handle_message(
        topic(),
        state(
            header_id=4,
            maps=[("demo", "1", "DISABLED"), ("demo", "r2", "ENABLED")],
            actions=((download_id, "FINISHED"), (enable_id, "FINISHED")),
        ),
    )
    kind, params, delete_id = actions(sent)[-1]
    assert (kind, params) == ("deleteMap", {"mapId": "demo", "mapVersion": "1"})

    controller.handle_message(
        topic(),
        state(
            header_id=5,
            maps=[("demo", "r2", "ENABLED")],
            actions=((download_id, "FINISHED"), (enable_id, "FINISHED"), (delete_id, "FINISHED")),
        ),
    )
    assert [a[0] for a in actions(sent)].count("deleteMap") == 1
    status = controller.distribution.maps.statuses[(("sim", "AGV-1"), "demo")]
    assert (status.status, status.enabled_version, status.released_version) == (
        "SYNCED",
        "r2",
        "r2",
    )
    rows = controller.distribution.collect_statuses()
    assert [(pk, s.map_id, s.status) for pk, s, *_ in rows] == [(1, "demo", "SYNCED")]


def test_K47_orders_wait_until_the_released_version_is_enabled(
    controller, sent, protocol_version
) -> None:
    with_map_distribution(protocol_version)
    online(controller, maps=OLD)
    release(controller)

    controller.sync([order()])

    assert orders_in(sent) == []
    status = controller.distribution.maps.statuses[(("sim", "AGV-1"), "demo")]
    assert status.reason == (
        "vehicle has map demo version 1 enabled, the released version is r2 (downloading)"
    )
    controller.handle_message(topic(), state(header_id=2, maps=[("demo", "r2", "ENABLED")]))
    controller.sync([order()])
    assert [m["orderId"] for m in orders_in(sent)] == ["TO-7"]


def test_K47_an_order_on_a_map_the_vehicle_has_not_enabled_is_held(
    controller, sent, protocol_version
) -> None:
    online(controller, maps=[("demo", "1", "DISABLED"), ("hall-2", "1", "ENABLED")])

    controller.sync([order()])

    if protocol_version == "2.0.0":  # no state.maps: nothing to check, the order goes out
        assert len(orders_in(sent)) == 1
        return
    assert orders_in(sent) == []
    assert controller.distribution.maps.hold_reason[("sim", "AGV-1")] == (
        "map demo is not enabled on the vehicle"
    )


def test_K47_a_2_0_vehicle_gets_no_map_actions(controller, sent, protocol_version) -> None:
    if protocol_version != "2.0.0":
        pytest.skip("2.0 only")
    online(controller, maps=OLD)
    release(controller)
    controller.sync([order()])
    assert not {"downloadMap", "enableMap", "deleteMap"} & {a[0] for a in actions(sent)}
    assert len(orders_in(sent)) == 1


def test_K47_a_failing_download_is_retried_then_the_map_is_failed_with_the_reason(
    controller, sent, protocol_version
) -> None:
    with_map_distribution(protocol_version)
    online(controller, maps=OLD)
    release(controller)
    for attempt in range(3):
        _, _, action_id = actions(sent)[-1]
        header = 10 + attempt
        controller.handle_message(
            topic(), state(header_id=header, maps=OLD, actions=((action_id, "FAILED"),))
        )
    downloads = [a for a in actions(sent) if a[0] == "downloadMap"]
    assert len(downloads) == 3
    status = controller.distribution.maps.statuses[(("sim", "AGV-1"), "demo")]
    assert status.status == "FAILED"
    assert status.reason.startswith("downloadMap FAILED")


def test_K47_an_unanswered_download_is_sent_again_after_the_retry_time(
    controller, sent, protocol_version
) -> None:
    with_map_distribution(protocol_version)
    online(controller, maps=OLD)
    release(controller)
    vehicle = controller.fleet.by_pk(1)
    sync = controller.distribution.maps
    sync.step(vehicle, now=1e12)  # long after the first send, still no actionState
    downloads = [a for a in actions(sent) if a[0] == "downloadMap"]
    assert len(downloads) == 2
    assert downloads[0][2] != downloads[1][2]  # a new actionId for the new attempt


def test_K47_without_a_factsheet_declaring_map_actions_the_vehicle_is_unsupported(
    controller, sent, protocol_version
) -> None:
    with_map_distribution(protocol_version)
    controller.handle_message(topic(), state(header_id=1, maps=OLD))  # no factsheet
    release(controller)
    controller.sync([order()])
    assert actions(sent) == [] or {a[0] for a in actions(sent)} <= {"factsheetRequest"}
    status = controller.distribution.maps.statuses[(("sim", "AGV-1"), "demo")]
    assert status.status == "UNSUPPORTED"
    assert len(orders_in(sent)) == 1  # it cannot be updated, so it is not held for it
    assert fakes.PROTOCOL["version"] == protocol_version


def test_K47_enable_map_waits_until_the_vehicle_has_finished_its_order(
    controller, sent, protocol_version
) -> None:
    with_map_distribution(protocol_version)
    downloaded = [*OLD, ("demo", "r2", "DISABLED")]
    online(controller, maps=downloaded, order_id="OTHER", nodes=("b", "c"))
    release(controller)

    assert "enableMap" not in [a[0] for a in actions(sent)]
    status = controller.distribution.maps.statuses[(("sim", "AGV-1"), "demo")]
    assert status.reason == "enableMap waits until the vehicle has finished its order"

    controller.handle_message(topic(), state(header_id=2, maps=downloaded, order_id="OTHER"))
    assert [a[0] for a in actions(sent)][-1] == "enableMap"


def test_K47_statuses_whose_write_failed_are_collected_again(
    controller, sent, protocol_version
) -> None:
    with_map_distribution(protocol_version)
    online(controller, maps=OLD)
    release(controller)
    rows = controller.distribution.collect_statuses()
    assert [s.status for _, s, *_ in rows] == ["DOWNLOADING"]
    assert controller.distribution.collect_statuses() == []

    controller.distribution.requeue(rows)

    assert [s.status for _, s, *_ in controller.distribution.collect_statuses()] == ["DOWNLOADING"]
