"""Writes of the layout editor: a whole map's layout saved atomically as a new version.

The editor posts the complete layout of one map (see `maps.services.editor_payload`). Saving
compares it with the database by id and writes only the differences, so rows the editor does not
show survive: LIF vehicle-type properties of nodes and edges, station heights, the LIF layout an
element came from, and transitions to other floors.
"""

import math
from collections.abc import Iterable
from typing import Any

from django.contrib.auth.base_user import AbstractBaseUser
from django.contrib.auth.models import AnonymousUser, User
from django.db import transaction
from django.db.models import F, ProtectedError, Q

from fleet import audit
from fleet.exceptions import DomainError, InvalidRequestError
from maps.models import Edge, Map, MapVersion, Node, Station, StationNode, VehicleType, Zone
from maps.selectors.editor import transition_edge_ids
from maps.selectors.validation import Finding, validate_layout
from maps.services.editor_payload import Draft, Problem, read_payload
from maps.services.layouts import mark_layout_changed
from maps.services.zones import counter_clockwise

BATCH = 2000
LENGTH_TOLERANCE = 1e-9


class LayoutPayloadError(InvalidRequestError):
    """A payload the editor cannot save; `problems` lists every problem with its path."""

    def __init__(self, problems: list[Problem]) -> None:
        self.problems = problems
        super().__init__(f"the layout has {len(problems)} problem(s); nothing was saved")


class LayoutConflictError(DomainError):
    """The map changed since the editor loaded it (HTTP 409)."""


class _Rollback(Exception):
    """Undoes the writes of a trial save."""


def save_layout_version(
    *, map: Map, payload: Any, user: AbstractBaseUser | AnonymousUser | None = None
) -> MapVersion:
    """Replace the layout of `map` by the editor's `payload` and record it as a new version.

    All or nothing: raises LayoutPayloadError with every problem (by path) and writes nothing, or
    LayoutConflictError when `baseRevision` is not the map's revision any more (someone saved in
    between). On success the revision is bumped (routing caches drop the map) and `Map.version`
    counts up.
    """
    draft, problems = read_payload(payload)
    if problems:
        raise LayoutPayloadError(problems)
    with transaction.atomic():
        locked = Map.objects.select_for_update().get(pk=map.pk)
        _check_base(locked, draft)
        problems = _LayoutWriter(locked, draft).write()
        if problems:
            raise LayoutPayloadError(problems)
        mark_layout_changed(maps=[locked])
        locked.refresh_from_db(fields=["revision", "version"])
        version = MapVersion.objects.create(
            map=locked,
            number=locked.version + 1,
            revision=locked.revision,
            saved_by=user if isinstance(user, User) else None,
            note=draft.note,
            counts={kind: len(getattr(draft, kind)) for kind in PARTS},
            layout=draft.as_dict(),
        )
        Map.objects.filter(pk=locked.pk).update(version=version.number)
        audit.record(
            "layout.save",
            target_type="map",
            target_id=locked.map_id,
            detail={"version": version.number, "counts": version.counts, "note": draft.note},
        )
    map.refresh_from_db()
    return version


def check_layout_draft(*, map: Map, payload: Any) -> tuple[list[Problem], list[Finding]]:
    """The problems of an unsaved payload, or else the validation findings it would have.

    The payload is written in a transaction that is rolled back, so the findings are exactly
    those `validate_layout` reports after saving, and nothing changes.
    """
    draft, problems = read_payload(payload)
    if problems:
        return problems, []
    findings: list[Finding] = []
    try:
        with transaction.atomic():
            locked = Map.objects.select_for_update().get(pk=map.pk)
            problems = _LayoutWriter(locked, draft).write()
            if not problems:
                mark_layout_changed(maps=[locked])  # a fresh graph for the trial layout
                locked.refresh_from_db()
                findings = validate_layout(map=locked)
            raise _Rollback
    except _Rollback:
        pass
    return problems, findings


PARTS = ("nodes", "edges", "stations", "zones")


def _check_base(layout: Map, draft: Draft) -> None:
    if draft.base_revision is not None and draft.base_revision != layout.revision:
        raise LayoutConflictError(
            f"map {layout.map_id} changed since the editor loaded it (revision "
            f"{draft.base_revision}, now {layout.revision}): reload it and redo your changes"
        )


class _LayoutWriter:
    """Writes the differences between a checked draft and one map's rows."""

    def __init__(self, layout: Map, draft: Draft) -> None:
        self.map, self.draft = layout, draft
        self.problems: list[Problem] = []
        self.nodes: dict[str, Node] = {}
        self.removed: set[int] = set()

    def write(self) -> list[Problem]:
        existing = {n.node_id: n for n in Node.objects.filter(map=self.map).order_by()}
        removed = [n.pk for node_id, n in existing.items() if node_id not in self.draft.nodes]
        self.removed = set(removed)
        self._check_site_ids()
        self._check_transitions(removed)
        if self.problems:
            return self.problems
        self._write_zones()
        self._write_nodes(existing)
        self._write_stations()
        if self.problems:
            return self.problems
        self._write_edges()
        Node.objects.filter(pk__in=removed).delete()
        self._write_floor_plan()
        return self.problems

    # ---------------------------------------------------------------- checks

    def _check_site_ids(self) -> None:
        """Node, edge and station ids stay unique across the maps of a site."""
        transitions = set(transition_edge_ids(self.map))
        for edge_id in sorted(transitions & self.draft.edges.keys()):
            self._problem(
                f"{self.draft.path('edges', edge_id)}.id",
                f"{edge_id} is the id of a transition to another floor on this map",
            )
        if self.map.site_id is None:
            return
        others = Map.objects.filter(site_id=self.map.site_id).exclude(pk=self.map.pk)
        for kind, model, field in (
            ("nodes", Node, "node_id"),
            ("edges", Edge, "edge_id"),
            ("stations", Station, "station_id"),
        ):
            ids = getattr(self.draft, kind).keys()
            taken = model.objects.filter(map__in=others, **{f"{field}__in": list(ids)})
            for element_id, other in taken.values_list(field, "map__map_id"):
                self._problem(
                    f"{self.draft.path(kind, element_id)}.id",
                    f"{element_id} is used on map {other} of the same site",
                )

    def _check_transitions(self, removed: list[int]) -> None:
        """Deleting a node must not silently delete a lift or ramp to another floor."""
        between_floors = Edge.objects.filter(Q(start__in=removed) | Q(end__in=removed)).exclude(
            start__map=F("end__map")
        )
        for edge_id, start, end in between_floors.values_list(
            "edge_id", "start__node_id", "end__node_id"
        ):
            node_id = start if start not in self.draft.nodes else end
            self._problem(
                "$.nodes",
                f"node {node_id} cannot be deleted: edge {edge_id} joins it to another floor "
                "(delete that edge in the admin first)",
            )

    # ---------------------------------------------------------------- writes

    def _write_zones(self) -> None:
        existing = {z.zone_id: z for z in Zone.objects.filter(map=self.map)}
        Zone.objects.filter(
            pk__in=[z.pk for zone_id, z in existing.items() if zone_id not in self.draft.zones]
        ).delete()
        types = {t.type_id: t for t in VehicleType.objects.all()}
        for zone_id, spec in self.draft.zones.items():
            fields = {k: v for k, v in spec.items() if k != "vehicle_types"}
            fields["vertices"] = counter_clockwise(fields["vertices"])
            wanted = {types[t] for t in spec["vehicle_types"]}
            zone = existing.get(zone_id)
            if zone is None:
                zone = Zone.objects.create(map=self.map, zone_id=zone_id, **fields)
                zone.vehicle_types.set(wanted)
                continue
            if any(getattr(zone, k) != v for k, v in fields.items()):
                for name, value in fields.items():
                    setattr(zone, name, value)
                zone.save()
            if set(zone.vehicle_types.all()) != wanted:
                zone.vehicle_types.set(wanted)

    def _write_nodes(self, existing: dict[str, Node]) -> None:
        new, changed = [], []
        for node_id, spec in self.draft.nodes.items():
            node = existing.get(node_id)
            if node is None:
                new.append(Node(map=self.map, node_id=node_id, **spec))
            elif any(getattr(node, k) != v for k, v in spec.items()):
                for name, value in spec.items():
                    setattr(node, name, value)
                changed.append(node)
        Node.objects.bulk_create(new, batch_size=BATCH)
        Node.objects.bulk_update(changed, ["x", "y", "theta", "name"], batch_size=BATCH)
        self.nodes = {n.node_id: n for n in Node.objects.filter(map=self.map).order_by()}

    def _write_stations(self) -> None:
        existing = {s.station_id: s for s in Station.objects.filter(map=self.map)}
        gone = [s for station_id, s in existing.items() if station_id not in self.draft.stations]
        self._delete_stations(gone)
        current = _interaction_nodes(existing.values())
        for station_id, spec in self.draft.stations.items():
            primary = self.nodes[spec["nodes"][0]]
            station = existing.get(station_id)
            if station is None:
                station = Station.objects.create(
                    map=self.map,
                    station_id=station_id,
                    name=spec["name"],
                    kind=spec["kind"],
                    node=primary,
                )
            elif (station.name, station.kind, station.node_id) != (
                spec["name"],
                spec["kind"],
                primary.pk,
            ):
                station.name, station.kind, station.node = spec["name"], spec["kind"], primary
                station.save(update_fields=["name", "kind", "node"])
            if current.get(station.pk) != spec["nodes"]:
                StationNode.objects.filter(station=station).delete()
                StationNode.objects.bulk_create(
                    StationNode(station=station, node=self.nodes[node_id], position=i)
                    for i, node_id in enumerate(spec["nodes"])
                )

    def _delete_stations(self, stations: list[Station]) -> None:
        for station in stations:
            try:
                with transaction.atomic():
                    station.delete()
            except ProtectedError as exc:
                refs = sorted({str(obj) for obj in exc.protected_objects})[:3]
                self._problem(
                    "$.stations",
                    f"station {station.station_id} cannot be deleted: still used by "
                    f"{', '.join(refs)}",
                )

    def _write_edges(self) -> None:
        own = {node.pk for node in self.nodes.values()} | self.removed
        edges = Edge.objects.filter(map=self.map).order_by()
        existing = {e.edge_id: e for e in edges if e.end_id in own}
        Edge.objects.filter(
            pk__in=[e.pk for edge_id, e in existing.items() if edge_id not in self.draft.edges]
        ).delete()
        new, changed = [], []
        for edge_id, spec in self.draft.edges.items():
            start, end = self.nodes[spec["start"]], self.nodes[spec["end"]]
            length = math.hypot(end.x - start.x, end.y - start.y)
            edge = existing.get(edge_id)
            if edge is None:
                new.append(
                    Edge(
                        map=self.map,
                        edge_id=edge_id,
                        start=start,
                        end=end,
                        length=length,
                        max_speed=spec["max_speed"],
                        name=spec["name"],
                    )
                )
            elif _edge_changed(edge, start, end, length, spec):
                edge.start, edge.end, edge.length = start, end, length
                edge.max_speed, edge.name = spec["max_speed"], spec["name"]
                changed.append(edge)
        Edge.objects.bulk_create(new, batch_size=BATCH)
        Edge.objects.bulk_update(
            changed, ["start", "end", "length", "max_speed", "name"], batch_size=BATCH
        )

    def _write_floor_plan(self) -> None:
        plan = self.draft.floor_plan
        if plan is None:
            return
        if any(getattr(self.map, k) != v for k, v in plan.items()):
            Map.objects.filter(pk=self.map.pk).update(**plan)

    def _problem(self, path: str, message: str) -> None:
        self.problems.append(Problem(path, message))


def _interaction_nodes(stations: Iterable[Station]) -> dict[int, list[str]]:
    found: dict[int, list[str]] = {}
    rows = StationNode.objects.filter(station__in=list(stations)).order_by("station", "position")
    for station_pk, node_id in rows.values_list("station_id", "node__node_id"):
        found.setdefault(station_pk, []).append(node_id)
    return found


def _edge_changed(edge: Edge, start: Node, end: Node, length: float, spec: dict[str, Any]) -> bool:
    return (
        edge.start_id != start.pk
        or edge.end_id != end.pk
        or abs(edge.length - length) > LENGTH_TOLERANCE
        or edge.max_speed != spec["max_speed"]
        or edge.name != spec["name"]
    )
