"""Reading the vehicle-type properties of LIF nodes and edges: actions, load, trajectory."""

from typing import Any

from maps.lif.document import EdgeProps, NodeProps
from maps.lif.reader import Reader, show
from traffic import Nurbs

REQUIREMENT_TYPES = ("REQUIRED", "CONDITIONAL", "OPTIONAL")
BLOCKING_TYPES = ("NONE", "SOFT", "HARD")
ORIENTATION_TYPES = ("GLOBAL", "TANGENTIAL")
ROTATIONS = ("NONE", "CCW", "CW", "BOTH")
ACTION_KEYS = (
    "actionType",
    "actionDescription",
    "requirementType",
    "blockingType",
    "actionParameters",
)
NODE_PROPERTY_KEYS = ("vehicleTypeId", "theta", "actions")
EDGE_PROPERTY_KEYS = (
    "vehicleTypeId",
    "vehicleOrientation",
    "orientationType",
    "rotationAllowed",
    "rotationAtStartNodeAllowed",
    "rotationAtEndNodeAllowed",
    "maxSpeed",
    "maxRotationSpeed",
    "minHeight",
    "maxHeight",
    "loadRestriction",
    "actions",
    "trajectory",
    "reentryAllowed",
)


def read_actions(reader: Reader, data: dict[str, Any], path: str) -> list[dict[str, Any]]:
    """The `actions` of a property, checked, in LIF key order."""
    actions = []
    for i, raw in enumerate(reader.array(data, "actions", path) or []):
        where = f"{path}.actions[{i}]"
        item = reader.obj(raw, where)
        if item is None:
            continue
        reader.known(item, where, "action", ACTION_KEYS)
        action: dict[str, Any] = {
            "actionType": reader.string(item, "actionType", where, required=True)
        }
        if description := reader.string(item, "actionDescription", where):
            action["actionDescription"] = description
        if requirement := reader.choice(item, "requirementType", where, REQUIREMENT_TYPES):
            action["requirementType"] = requirement
        action["blockingType"] = reader.choice(
            item, "blockingType", where, BLOCKING_TYPES, required=True
        )
        parameters = reader.array(item, "actionParameters", where)
        if parameters is not None:
            action["actionParameters"] = _parameters(reader, parameters, where)
        actions.append(action)
    return actions


def _parameters(reader: Reader, parameters: list[Any], path: str) -> list[dict[str, Any]]:
    result = []
    for j, raw in enumerate(parameters):
        where = f"{path}.actionParameters[{j}]"
        item = reader.obj(raw, where)
        if item is None:
            continue
        key = reader.string(item, "key", where, required=True)
        if "value" not in item:
            reader.report.error(f"{where}.value", "missing required field")
        elif not isinstance(item["value"], str):
            reader.report.warn(
                f"{where}.value", f"LIF values are strings; kept {show(item['value'])}"
            )
        result.append({"key": key, "value": item.get("value")})
    return result


def read_node_props(reader: Reader, raw: Any, path: str) -> NodeProps | None:
    item = reader.obj(raw, path)
    if item is None:
        return None
    reader.known(item, path, "vehicleTypeNodeProperty", NODE_PROPERTY_KEYS)
    return NodeProps(
        vehicle_type=reader.string(item, "vehicleTypeId", path, required=True),
        theta=reader.number(item, "theta", path),
        actions=read_actions(reader, item, path),
    )


def read_edge_props(reader: Reader, raw: Any, path: str) -> EdgeProps | None:
    item = reader.obj(raw, path)
    if item is None:
        return None
    reader.known(item, path, "vehicleTypeEdgeProperty", EDGE_PROPERTY_KEYS)
    props = EdgeProps(
        vehicle_type=reader.string(item, "vehicleTypeId", path, required=True),
        rotation_allowed=bool(reader.boolean(item, "rotationAllowed", path, required=True)),
        vehicle_orientation=reader.number(item, "vehicleOrientation", path),
        orientation_type=reader.choice(item, "orientationType", path, ORIENTATION_TYPES),
        rotation_at_start=reader.choice(item, "rotationAtStartNodeAllowed", path, ROTATIONS),
        rotation_at_end=reader.choice(item, "rotationAtEndNodeAllowed", path, ROTATIONS),
        max_speed=reader.number(item, "maxSpeed", path, positive=True),
        max_rotation_speed=reader.number(item, "maxRotationSpeed", path, positive=True),
        min_height=reader.number(item, "minHeight", path, minimum=0.0),
        max_height=reader.number(item, "maxHeight", path, minimum=0.0),
        actions=read_actions(reader, item, path),
        reentry_allowed=reader.boolean(item, "reentryAllowed", path),
    )
    if "loadRestriction" in item:
        _load_restriction(reader, item["loadRestriction"], f"{path}.loadRestriction", props)
    if "trajectory" in item:
        props.trajectory = read_trajectory(reader, item["trajectory"], f"{path}.trajectory")
    return props


def _load_restriction(reader: Reader, raw: Any, path: str, props: EdgeProps) -> None:
    item = reader.obj(raw, path)
    if item is None:
        return
    reader.known(item, path, "loadRestriction", ("unloaded", "loaded", "loadSetNames"))
    props.load_unloaded = reader.boolean(item, "unloaded", path, required=True)
    props.load_loaded = reader.boolean(item, "loaded", path, required=True)
    props.load_set_names = reader.strings(item, "loadSetNames", path)


def read_trajectory(reader: Reader, raw: Any, path: str) -> dict[str, Any] | None:
    """A NURBS trajectory, checked for consistency (knots, degree, weights) by traffic.Nurbs."""
    item = reader.obj(raw, path)
    if item is None:
        return None
    reader.known(item, path, "trajectory", ("degree", "knotVector", "controlPoints"))
    errors = len(reader.report.errors)
    degree = reader.number(item, "degree", path, minimum=1.0)
    if degree is not None and degree != int(degree):
        reader.report.error(f"{path}.degree", f"must be a whole number, got {degree:g}")
    knots = reader.array(item, "knotVector", path, required=True) or []
    for i, knot in enumerate(knots):
        if not isinstance(knot, int | float) or isinstance(knot, bool) or not 0.0 <= knot <= 1.0:
            reader.report.error(
                f"{path}.knotVector[{i}]", f"expected a number in [0, 1], got {show(knot)}"
            )
    points = []
    for i, raw_point in enumerate(reader.array(item, "controlPoints", path, required=True) or []):
        where = f"{path}.controlPoints[{i}]"
        point = reader.obj(raw_point, where)
        if point is None:
            continue
        reader.known(point, where, "controlPoint", ("x", "y", "weight"))
        x, y = (
            reader.number(point, "x", where, required=True),
            reader.number(point, "y", where, required=True),
        )
        weight = reader.number(point, "weight", where, positive=True)
        entry: dict[str, Any] = {"x": x, "y": y}
        if weight is not None:
            entry["weight"] = weight
        points.append(entry)
    trajectory: dict[str, Any] = {"knotVector": knots, "controlPoints": points}
    if degree is not None:
        trajectory = {"degree": int(degree), **trajectory}
    if len(reader.report.errors) == errors:
        try:
            nurbs_of(trajectory)
        except ValueError as exc:
            reader.report.error(path, f"not a valid NURBS: {exc}")
    return trajectory


def nurbs_of(trajectory: dict[str, Any]) -> Nurbs:
    """The traffic.Nurbs of a LIF trajectory (degree defaults to 1, weights to 1.0)."""
    return Nurbs(
        degree=int(trajectory.get("degree") or 1),
        knots=tuple(float(k) for k in trajectory["knotVector"]),
        points=tuple(
            (float(p["x"]), float(p["y"]), float(p.get("weight") or 1.0))
            for p in trajectory["controlPoints"]
        ),
    )
