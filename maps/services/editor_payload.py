"""The layout editor's payload: checked field by field, every problem reported with its path.

The payload is the whole layout of one map, in the shape `maps.selectors.editor_data` gives it:

    {"baseRevision": 7, "note": "...",
     "floorPlan": {"scale": 0.05, "originX": 0, "originY": 0, "rotation": 0},
     "nodes": [{"id", "x", "y", "theta"?, "name"?}],
     "edges": [{"id", "start", "end", "maxSpeed"?, "name"?}],
     "stations": [{"id", "name"?, "kind", "nodes": [interaction node ids, primary first]}],
     "zones": [{"id", "type", "vertices": [{x, y}], "name"?, "enabled"?, "maxSpeed"?, ...}]}

Paths are JSONPath-like ("$.edges[4].end"), as in LIF import reports.
"""

from dataclasses import dataclass, field
from typing import Any

from maps.models import Station, VehicleType, Zone
from maps.services.payload_fields import FieldReader, Problem, show_value
from maps.zoning import ZONE_RULE_FIELDS, zone_problems

__all__ = ["Draft", "PayloadReader", "Problem", "read_payload"]

MAX_ID = 100
MAX_NAME = 200
BLOCKING_TYPES = ("NONE", "SOFT", "SINGLE", "HARD")
ZONE_KEYS = {  # payload key -> Zone field
    "type": "zone_type",
    "vertices": "vertices",
    "name": "name",
    "description": "description",
    "enabled": "enabled",
    "maxSpeed": "max_speed",
    "direction": "direction",
    "limitation": "limitation",
    "penaltyFactor": "penalty_factor",
    "priorityFactor": "priority_factor",
    "releaseLossBehavior": "release_loss_behavior",
    "entryActions": "entry_actions",
    "duringActions": "during_actions",
    "exitActions": "exit_actions",
}
ZONE_PATHS = {model: key for key, model in ZONE_KEYS.items()}
FLOOR_PLAN_KEYS = {
    "scale": "floor_plan_scale",
    "originX": "floor_plan_origin_x",
    "originY": "floor_plan_origin_y",
    "rotation": "floor_plan_rotation",
}


@dataclass
class Draft:
    """A checked payload: elements by id, with the path each came from."""

    base_revision: int | None = None
    note: str = ""
    floor_plan: dict[str, float | None] | None = None
    nodes: dict[str, dict[str, Any]] = field(default_factory=dict)
    edges: dict[str, dict[str, Any]] = field(default_factory=dict)
    stations: dict[str, dict[str, Any]] = field(default_factory=dict)
    zones: dict[str, dict[str, Any]] = field(default_factory=dict)
    paths: dict[tuple[str, str], str] = field(default_factory=dict)

    def path(self, kind: str, element_id: str) -> str:
        return self.paths.get((kind, element_id), f"$.{kind}")

    def as_dict(self) -> dict[str, Any]:
        """The layout as saved (for `MapVersion.layout`)."""
        zones = []
        for zone_id, spec in self.zones.items():
            data = {key: spec[model] for key, model in ZONE_KEYS.items() if model in spec}
            zones.append({"id": zone_id, **data, "vehicleTypes": spec["vehicle_types"]})
        return {
            "floorPlan": self.floor_plan,
            "nodes": [{"id": k, **v} for k, v in self.nodes.items()],
            "edges": [
                {"id": k, "start": v["start"], "end": v["end"], "maxSpeed": v["max_speed"]}
                | ({"name": v["name"]} if v["name"] else {})
                for k, v in self.edges.items()
            ],
            "stations": [{"id": k, **v} for k, v in self.stations.items()],
            "zones": zones,
        }


class PayloadReader(FieldReader):
    """Reads a payload into a Draft, collecting every problem instead of stopping at the first."""

    def __init__(self) -> None:
        super().__init__()
        self.draft = Draft()

    def read(self, payload: Any) -> Draft:
        root = self._object(payload, "$")
        if root is None:
            return self.draft
        self._known(root, "$", {"baseRevision", "note", "floorPlan", *LISTS})
        revision = root.get("baseRevision")
        if revision is not None and (not isinstance(revision, int) or isinstance(revision, bool)):
            self._problem("$.baseRevision", "must be a whole number")
        else:
            self.draft.base_revision = revision
        self.draft.note = self._text(root, "note", "$", 500)
        if root.get("floorPlan") is not None:
            self._floor_plan(root["floorPlan"])
        for kind, read in (
            ("nodes", self._node),
            ("edges", self._edge),
            ("stations", self._station),
            ("zones", self._zone),
        ):
            for i, item in enumerate(self._list(root, kind, "$")):
                read(item, f"$.{kind}[{i}]")
        return self.draft

    # ---------------------------------------------------------------- elements

    def _floor_plan(self, raw: Any) -> None:
        data = self._object(raw, "$.floorPlan")
        if data is None:
            return
        self._known(data, "$.floorPlan", set(FLOOR_PLAN_KEYS))
        plan = {
            model: self._number(data, key, "$.floorPlan", positive=key == "scale")
            for key, model in FLOOR_PLAN_KEYS.items()
        }
        for key in ("originX", "originY", "rotation"):
            plan[FLOOR_PLAN_KEYS[key]] = plan[FLOOR_PLAN_KEYS[key]] or 0.0
        self.draft.floor_plan = plan

    def _node(self, raw: Any, path: str) -> None:
        data = self._object(raw, path)
        if data is None:
            return
        self._known(data, path, {"id", "x", "y", "theta", "name"})
        node_id = self._id(data, path, "nodes")
        spec = {
            "x": self._number(data, "x", path, required=True),
            "y": self._number(data, "y", path, required=True),
            "theta": self._number(data, "theta", path),
            "name": self._text(data, "name", path, MAX_NAME),
        }
        if node_id is not None:
            self.draft.nodes[node_id] = spec

    def _edge(self, raw: Any, path: str) -> None:
        data = self._object(raw, path)
        if data is None:
            return
        self._known(data, path, {"id", "start", "end", "maxSpeed", "name"})
        edge_id = self._id(data, path, "edges")
        start, end = self._ref(data, "start", path), self._ref(data, "end", path)
        if start is not None and start == end:
            self._problem(f"{path}.end", "an edge must end at another node than it starts")
        spec = {
            "start": start,
            "end": end,
            "max_speed": self._number(data, "maxSpeed", path, positive=True),
            "name": self._text(data, "name", path, MAX_NAME),
        }
        if edge_id is not None and start is not None and end is not None:
            self.draft.edges[edge_id] = spec

    def _station(self, raw: Any, path: str) -> None:
        data = self._object(raw, path)
        if data is None:
            return
        self._known(data, path, {"id", "name", "kind", "nodes"})
        station_id = self._id(data, path, "stations")
        kind = data.get("kind")
        if kind not in Station.Kind.values:
            self._problem(f"{path}.kind", f"must be one of {', '.join(Station.Kind.values)}")
        raw = data.get("nodes")
        nodes: list[str] = []
        if isinstance(raw, list) and raw and all(isinstance(n, str) for n in raw):
            nodes = raw
            self._check_station_nodes(nodes, f"{path}.nodes")
        else:
            self._problem(f"{path}.nodes", "needs a list of at least one node id")
        spec = {"name": self._text(data, "name", path, MAX_NAME), "kind": kind, "nodes": nodes}
        if station_id is not None and nodes:
            self.draft.stations[station_id] = spec

    def _zone(self, raw: Any, path: str) -> None:
        data = self._object(raw, path)
        if data is None:
            return
        self._known(data, path, {"id", "vehicleTypes", *ZONE_KEYS})
        zone_id = self._id(data, path, "zones")
        zone_type = data.get("type")
        if zone_type not in Zone.Type.values:
            self._problem(f"{path}.type", f"unknown zone type {show_value(zone_type)}")
        spec: dict[str, Any] = {
            "zone_type": zone_type,
            "vertices": data.get("vertices"),
            "name": self._text(data, "name", path, MAX_NAME),
            "description": self._text(data, "description", path, 10_000),
            "enabled": self._flag(data, "enabled", path, default=True),
            "max_speed": self._number(data, "maxSpeed", path, positive=True),
            "direction": self._number(data, "direction", path),
            "limitation": self._choice(data, "limitation", path, Zone.Limitation.values),
            "penalty_factor": self._number(data, "penaltyFactor", path, unit=True),
            "priority_factor": self._number(data, "priorityFactor", path, unit=True),
            "release_loss_behavior": self._choice(
                data, "releaseLossBehavior", path, Zone.ReleaseLoss.values
            ),
            "vehicle_types": self._vehicle_types(data, path),
        }
        for key in ("entryActions", "duringActions", "exitActions"):
            spec[ZONE_KEYS[key]] = self._actions(data, key, path)
        if zone_type in Zone.Type.values:
            rule_fields = {k: spec[k] for k in ZONE_RULE_FIELDS}
            for model_field, message in zone_problems(**rule_fields):
                self._problem(f"{path}.{ZONE_PATHS[model_field]}", message)
        if zone_id is not None:
            self.draft.zones[zone_id] = spec

    # ---------------------------------------------------------------- references

    def check_references(self) -> None:
        """Edges and stations name nodes of the payload (after every node was read)."""
        nodes = self.draft.nodes
        pairs: dict[tuple[str, str], str] = {}
        for edge_id, spec in list(self.draft.edges.items()):
            path = self.draft.path("edges", edge_id)
            for end in ("start", "end"):
                if spec[end] not in nodes:
                    self._problem(f"{path}.{end}", f"unknown node {show_value(spec[end])}")
            pair = (spec["start"], spec["end"])
            if pair in pairs:
                self._problem(path, f"edge {pairs[pair]} already runs from {pair[0]} to {pair[1]}")
            pairs.setdefault(pair, edge_id)
        for station_id, spec in self.draft.stations.items():
            path = self.draft.path("stations", station_id)
            for i, node_id in enumerate(spec["nodes"]):
                if node_id not in nodes:
                    self._problem(f"{path}.nodes[{i}]", f"unknown node {show_value(node_id)}")

    def _check_station_nodes(self, nodes: list[str], path: str) -> None:
        seen: set[str] = set()
        for i, node_id in enumerate(nodes):
            if node_id in seen:
                self._problem(f"{path}[{i}]", f"node {node_id} is listed twice")
            seen.add(node_id)

    def _vehicle_types(self, data: dict[str, Any], path: str) -> list[str]:
        names = data.get("vehicleTypes") or []
        if not isinstance(names, list) or not all(isinstance(n, str) for n in names):
            self._problem(f"{path}.vehicleTypes", "must be a list of vehicle type ids")
            return []
        known = set(VehicleType.objects.filter(type_id__in=names).values_list("type_id", flat=True))
        for i, name in enumerate(names):
            if name not in known:
                self._problem(
                    f"{path}.vehicleTypes[{i}]", f"unknown vehicle type {show_value(name)}"
                )
        return [n for n in names if n in known]

    def _actions(self, data: dict[str, Any], key: str, path: str) -> list[dict[str, Any]]:
        actions = data.get(key)
        if actions is None:
            return []
        if not isinstance(actions, list):
            self._problem(f"{path}.{key}", "must be a list of actions")
            return []
        for i, action in enumerate(actions):
            where = f"{path}.{key}[{i}]"
            if not isinstance(action, dict) or not isinstance(action.get("actionType"), str):
                self._problem(where, "an action needs an actionType")
            elif action.get("blockingType") not in BLOCKING_TYPES:
                self._problem(
                    f"{where}.blockingType", f"must be one of {', '.join(BLOCKING_TYPES)}"
                )
        return actions

    # ---------------------------------------------------------------- fields

    def _id(self, data: dict[str, Any], path: str, kind: str) -> str | None:
        value = data.get("id")
        if not isinstance(value, str) or not value.strip():
            self._problem(f"{path}.id", "needs an id")
            return None
        if len(value) > MAX_ID or value != value.strip():
            self._problem(f"{path}.id", f"ids have 1 to {MAX_ID} characters, no outer spaces")
            return None
        if (kind, value) in self.draft.paths:
            first = self.draft.paths[(kind, value)]
            self._problem(f"{path}.id", f"{value} is used twice (also at {first})")
            return None
        self.draft.paths[(kind, value)] = path
        return value

    def _ref(self, data: dict[str, Any], key: str, path: str) -> str | None:
        value = data.get(key)
        if not isinstance(value, str) or not value:
            self._problem(f"{path}.{key}", "needs a node id")
            return None
        return value


LISTS = ("nodes", "edges", "stations", "zones")


def read_payload(payload: Any) -> tuple[Draft, list[Problem]]:
    """The draft of an editor payload and every problem found in it ([] when it is fine)."""
    reader = PayloadReader()
    draft = reader.read(payload)
    reader.check_references()
    return draft, reader.problems
