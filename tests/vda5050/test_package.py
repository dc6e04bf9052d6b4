"""Package contract: exported names, field names, Struct options, no framework imports."""

from __future__ import annotations

import enum
import inspect
import subprocess
import sys
from pathlib import Path

import msgspec
import pytest

import vda5050
from vda5050 import enums

PACKAGE_DIR = Path(vda5050.__file__).parent

# The naming contract other code is written against (class → fields that must exist).
CONTRACT: dict[str, set[str]] = {
    "Order": {
        "header_id",
        "timestamp",
        "version",
        "manufacturer",
        "serial_number",
        "order_id",
        "order_update_id",
        "zone_set_id",
        "nodes",
        "edges",
    },
    "Node": {
        "node_id",
        "sequence_id",
        "node_description",
        "released",
        "node_position",
        "actions",
    },
    "Edge": {
        "edge_id",
        "sequence_id",
        "released",
        "start_node_id",
        "end_node_id",
        "max_speed",
        "orientation",
        "orientation_type",
        "trajectory",
        "corridor",
        "actions",
    },
    "NodePosition": {
        "x",
        "y",
        "theta",
        "allowed_deviation_xy",
        "allowed_deviation_theta",
        "map_id",
    },
    "Action": {
        "action_type",
        "action_id",
        "action_description",
        "blocking_type",
        "action_parameters",
    },
    "ActionParameter": {"key", "value"},
    "Trajectory": {"degree", "knot_vector", "control_points"},
    "ControlPoint": {"x", "y", "weight"},
    "Corridor": {"left_width", "right_width", "corridor_ref_point"},
    "InstantActions": {"header_id", "actions"},
    "State": {
        "header_id",
        "timestamp",
        "version",
        "manufacturer",
        "serial_number",
        "maps",
        "order_id",
        "order_update_id",
        "last_node_id",
        "last_node_sequence_id",
        "node_states",
        "edge_states",
        "driving",
        "paused",
        "new_base_request",
        "distance_since_last_node",
        "operating_mode",
        "action_states",
        "battery_state",
        "errors",
        "information",
        "loads",
        "agv_position",
        "velocity",
        "safety_state",
    },
    "NodeState": {"node_id", "sequence_id", "released", "node_position"},
    "EdgeState": {"edge_id", "sequence_id", "released", "trajectory"},
    "ActionState": {
        "action_id",
        "action_type",
        "action_description",
        "action_status",
        "result_description",
    },
    "AgvPosition": {"x", "y", "theta", "map_id", "position_initialized"},
    "Velocity": {"vx", "vy", "omega"},
    "BatteryState": {"battery_charge", "charging"},
    "Error": {
        "error_type",
        "error_level",
        "error_description",
        "error_references",
        "error_hint",
    },
    "ErrorReference": {"reference_key", "reference_value"},
    "Information": {"info_type", "info_level", "info_references", "info_description"},
    "InfoReference": {"reference_key", "reference_value"},
    "Load": {"load_id", "load_type", "load_position", "load_dimensions", "weight"},
    "LoadDimensions": {"length", "width", "height"},
    "BoundingBoxReference": {"x", "y", "z", "theta"},
    "SafetyState": {"e_stop", "field_violation"},
    "MapState": {"map_id", "map_version", "map_description", "map_status"},
    "Connection": {"header_id", "connection_state"},
    "Visualization": {"header_id", "agv_position", "velocity"},
    "Factsheet": {
        "type_specification",
        "physical_parameters",
        "protocol_limits",
        "protocol_features",
        "agv_geometry",
        "load_specification",
        "vehicle_config",
    },
    "TypeSpecification": {"series_name", "agv_kinematic", "agv_class", "max_load_mass"},
    "PhysicalParameters": {"speed_min", "speed_max", "width", "length"},
    "ProtocolLimits": {"max_string_lens", "max_array_lens", "timing"},
    "MaxStringLens": {"msg_len", "id_len"},
    "MaxArrayLens": {"order_nodes", "order_edges"},
    "Timing": {"min_order_interval", "min_state_interval", "default_state_interval"},
    "ProtocolFeatures": {"optional_parameters", "agv_actions"},
    "OptionalParameter": {"parameter", "support"},
    "AgvAction": {"action_type", "action_scopes", "action_parameters", "blocking_types"},
    "ActionParameterSpec": {"key", "value_data_type", "is_optional"},
    "AgvGeometry": {"wheel_definitions", "envelopes2d", "envelopes3d"},
    "WheelDefinition": {"type", "position", "diameter", "width"},
    "Envelope2d": {"set", "polygon_points"},
    "Envelope3d": {"set", "format", "data", "url"},
    "PolygonPoint": {"x", "y"},
    "LoadSpecification": {"load_positions", "load_sets"},
    "LoadSet": {"set_name", "load_type"},
    "VehicleConfig": {"versions", "network"},
}

ENUMS = {
    "ConnectionState",
    "OperatingMode",
    "ActionStatus",
    "BlockingType",
    "ErrorLevel",
    "InfoLevel",
    "EStop",
    "OrientationType",
    "MapStatus",
    "TopicKind",
    "ProtocolVersion",
}


def _structs() -> list[type[msgspec.Struct]]:
    return [
        obj
        for obj in vars(vda5050).values()
        if isinstance(obj, type)
        and issubclass(obj, msgspec.Struct)
        and obj.__module__.startswith("vda5050.")
    ]


@pytest.mark.parametrize("name", sorted(CONTRACT))
def test_contract_fields_exist(name: str) -> None:
    cls = getattr(vda5050, name)
    assert CONTRACT[name] <= set(cls.__struct_fields__)


def test_everything_in_all_is_importable() -> None:
    for name in vda5050.__all__:
        assert hasattr(vda5050, name), name
    assert set(CONTRACT) <= set(vda5050.__all__)
    assert set(vda5050.__all__) >= ENUMS


def test_enums_are_str_enums_with_wire_values() -> None:
    for name in ENUMS:
        cls = getattr(enums, name)
        assert issubclass(cls, enum.StrEnum)
    assert enums.ConnectionState.CONNECTIONBROKEN == "CONNECTIONBROKEN"
    assert enums.OperatingMode.TEACHIN == "TEACHIN"
    assert enums.EStop.AUTOACK == "AUTOACK"
    assert [str(v) for v in enums.ProtocolVersion] == ["2.0.0", "2.1.0"]
    assert str(enums.TopicKind.INSTANT_ACTIONS) == "instantActions"


@pytest.mark.parametrize("cls", _structs(), ids=lambda c: c.__name__)
def test_struct_options(cls: type[msgspec.Struct]) -> None:
    assert cls.__doc__
    parameters = inspect.signature(cls).parameters.values()
    assert all(p.kind is inspect.Parameter.KEYWORD_ONLY for p in parameters)
    for field in msgspec.structs.fields(cls):
        # Optional fields default to None so that omit_defaults drops them (Trajectory.degree
        # is the documented exception: default 1, always sent).
        if not field.required and (cls.__name__, field.name) != ("Trajectory", "degree"):
            assert field.default is None, f"{cls.__name__}.{field.name}"
    assert cls.__struct_config__.omit_defaults is (cls.__name__ != "Trajectory")


def test_snake_case_attributes_map_to_camel_case_wire_names() -> None:
    explicit = {"allowedDeviationXY"}
    for cls in _structs():
        for field in msgspec.structs.fields(cls):
            if field.encode_name in explicit or "." in field.encode_name:
                continue
            head, *rest = field.name.split("_")
            assert field.encode_name == head + "".join(p.title() for p in rest), field


def test_package_imports_no_framework() -> None:
    code = (
        "import sys, vda5050, vda5050.codec, vda5050.builders;"
        "bad = {'django', 'celery', 'channels', 'rest_framework', 'paho'};"
        "loaded = sorted(m for m in sys.modules if m.split('.')[0] in bad);"
        "print(','.join(loaded))"
    )
    result = subprocess.run(  # noqa: S603
        [sys.executable, "-c", code],
        capture_output=True,
        text=True,
        check=True,
        cwd=PACKAGE_DIR.parent,
    )
    assert result.stdout.strip() == ""


def test_sources_do_not_mention_frameworks() -> None:
    for path in PACKAGE_DIR.rglob("*.py"):
        for line in path.read_text().splitlines():
            stripped = line.strip()
            if stripped.startswith(("import ", "from ")):
                assert not any(
                    word in stripped for word in ("django", "celery", "channels", "rest_framework")
                ), f"{path}: {stripped}"


def test_modules_stay_small() -> None:
    for path in PACKAGE_DIR.rglob("*.py"):
        assert len(path.read_text().splitlines()) <= 400, path
