"""LIF import and export: the official examples, round trips, malformed files, id clashes."""

import copy
import json

import pytest

from maps.lif.parse import parse_lif
from maps.models import Edge, EdgeProperty, LifImport, Map, Node, Site, Station, VehicleType
from maps.selectors import export_map_lif, export_site_lif, load_site_graph
from maps.services import import_lif
from tests.maps.support import EXAMPLE_FILES, example, lif, row_counts, snapshot, wipe

pytestmark = pytest.mark.django_db


def test_all_nineteen_official_examples_are_there() -> None:
    assert len(EXAMPLE_FILES) == 19


@pytest.mark.parametrize("path", EXAMPLE_FILES, ids=lambda p: p.name.split("_")[0])
def test_each_example_imports_re_exports_and_re_imports_to_the_same_model(path) -> None:
    report = import_lif(source=path.read_bytes(), site_id="plant", file_name=path.name)
    assert report.ok, report.lines()
    site = Site.objects.get(site_id="plant")
    before = snapshot(site)
    exported = export_site_lif(site=site)

    wipe(site)
    again = import_lif(source=json.dumps(exported), site_id="plant")

    assert again.ok, again.lines()
    assert again.warnings == []  # our own export is clean LIF 1.0
    assert snapshot(Site.objects.get(site_id="plant")) == before
    original = json.loads(path.read_text())
    assert len(before["nodes"]) == sum(len(la["nodes"]) for la in original["layouts"])
    assert len(before["edges"]) == sum(len(la["edges"]) for la in original["layouts"])


def test_the_examples_deviations_from_the_schema_are_warnings() -> None:
    report = import_lif(source=example("10.13_"), site_id="plant")

    assert report.ok
    warnings = [str(w) for w in report.warnings]
    assert "$.metaInformation.lifVersion: 0.11.0 predates LIF 1.0.0; read as 1.0.0" in warnings
    assert (
        '$.layouts[0].stations[0].stationHeight: number given as a string "0.0"; read as 0'
        in warnings
    )
    assert "stations" in str(import_lif(source=example("10.1_"), site_id="other").warnings)


def test_a_station_keeps_all_interaction_nodes_in_order_and_the_first_as_primary() -> None:
    import_lif(source=example("10.10_"), site_id="plant")

    station = Station.objects.get(station_id="NS")

    assert station.node.node_id == "NSL"
    assert [sn.node.node_id for sn in station.station_nodes.all()] == ["NSL", "NSB", "NSR"]
    assert station.height == 0.5
    assert station.kind == Station.Kind.HANDOVER  # pick and drop offered at its nodes


def test_station_kinds_are_inferred_from_node_actions() -> None:
    import_lif(source=example("10.13_"), site_id="a")
    import_lif(source=example("10.6_"), site_id="b")

    assert Station.objects.get(map__site__site_id="a").kind == Station.Kind.CHARGE
    assert Station.objects.get(map__site__site_id="b").kind == Station.Kind.PICK


def test_vehicle_type_properties_are_stored_as_lif_defines_them() -> None:
    import_lif(source=example("10.12_"), site_id="plant")

    stable = EdgeProperty.objects.get(edge__edge_id="N1-N0_Stable_Load")
    charger = Node.objects.get(node_id="N0").properties.get()

    assert (stable.vehicle_type.type_id, stable.max_speed) == ("Vehicle_Type_1", 0.8)
    assert (stable.load_unloaded, stable.load_loaded) == (False, True)
    assert stable.load_set_names == ["Stable_Load_Unit"]
    assert stable.rotation_at_end == "NONE"
    assert [a["actionType"] for a in charger.actions] == ["startCharging", "stopCharging"]
    assert Edge.objects.filter(start__node_id="N1", end__node_id="N0").count() == 2


def test_two_levels_become_two_maps_of_one_site_joined_by_transition_edges() -> None:
    import_lif(source=example("10.14_"), site_id="plant")

    maps = Map.objects.filter(site__site_id="plant").order_by("map_id")
    lift = Edge.objects.select_related("start__map", "end__map").get(edge_id="N2-N102")
    route = load_site_graph(site=Site.objects.get()).route("N1", "N101")

    assert [(m.map_id, m.level) for m in maps] == [("Map_Z-Level_1", "0"), ("Map_Z-Level_2", "1")]
    assert (lift.start.map.map_id, lift.end.map.map_id) == ("Map_Z-Level_1", "Map_Z-Level_2")
    assert route.map_ids == ["Map_Z-Level_1", "Map_Z-Level_2"]
    assert "N2-N102" not in json.dumps(export_map_lif(map=maps[0]))  # only in a site export


def malformed() -> dict:
    document = copy.deepcopy(example("10.7_"))
    layout = document["layouts"][0]
    layout["edges"][3]["startNodeId"] = "n9"
    layout["nodes"][1]["nodePosition"]["x"] = "far"
    layout["edges"][0]["vehicleTypeEdgeProperties"][0]["rotationAtStartNodeAllowed"] = "LEFT"
    layout["stations"][0]["interactionNodeIds"].append("ZZ")
    del layout["edges"][5]["vehicleTypeEdgeProperties"][0]["rotationAllowed"]
    return document


def test_a_malformed_file_reports_every_problem_with_its_path_and_writes_nothing(demo_map) -> None:
    import_lif(source=example("10.1_"), site_id="plant")
    before = row_counts()

    report = import_lif(source=malformed(), site_id="plant")

    assert not report.ok
    assert [str(e) for e in report.errors] == [
        "$.layouts[0].nodes[1].nodePosition.x: expected a number, got a string",
        '$.layouts[0].edges[0].vehicleTypeEdgeProperties[0].rotationAtStartNodeAllowed: "LEFT" '
        "is not one of NONE, CCW, CW, BOTH",
        "$.layouts[0].edges[5].vehicleTypeEdgeProperties[0].rotationAllowed: "
        "missing required field",
        '$.layouts[0].edges[3].startNodeId: unknown node "n9"',
        '$.layouts[0].stations[0].interactionNodeIds[2]: unknown node "ZZ"',
    ]
    assert row_counts() == before


@pytest.mark.parametrize(
    ("source", "expected"),
    [
        (b'{"metaInformation": {}, "layouts": [}', "$: not valid JSON: Expecting value at line 1"),
        (b"[1, 2]", "$: expected an object, got an array"),
        (
            {
                "metaInformation": {"projectIdentification": "x", "lifVersion": "2.0.0"},
                "layouts": [],
            },
            "$.metaInformation.lifVersion: LIF 2.0.0 is not supported (only 1.x)",
        ),
        ({"metaInformation": {"projectIdentification": "x"}}, "$.layouts: missing required field"),
    ],
)
def test_unreadable_files_are_refused_with_the_reason(source, expected) -> None:
    report = import_lif(source=source, site_id="plant")

    assert not report.ok
    assert str(report.errors[0]).startswith(expected)
    assert not Site.objects.exists()


def test_duplicate_ids_and_a_second_property_per_type_are_errors() -> None:
    document = lif([("a", 0, 0), ("b", 1, 0)], [("a", "b"), ("b", "a")])
    layout = document["layouts"][0]
    layout["nodes"][1]["nodeId"] = "a"
    layout["edges"][0]["vehicleTypeEdgeProperties"].append(
        {"vehicleTypeId": "AGV", "rotationAllowed": True}
    )

    errors = [str(e) for e in import_lif(source=document).errors]

    assert (
        '$.layouts[0].nodes[1].nodeId: duplicate node id "a" (also at $.layouts[0].nodes[0])'
        in errors
    )
    assert any("vehicleTypeEdgeProperties[1].vehicleTypeId: second property" in e for e in errors)


def test_a_second_file_with_clashing_ids_is_prefixed_by_its_project_with_a_warning() -> None:
    import_lif(source=example("10.1_"), site_id="plant")

    report = import_lif(source=example("10.2_"), site_id="plant")

    assert report.ok
    assert report.prefix == "lif-example-02:"
    (clash,) = [str(w) for w in report.warnings if w.path == "$"]
    assert "every id of this file is prefixed" in clash
    assert "nodes N1, N2" in clash
    node = Node.objects.get(node_id="lif-example-02:N1")
    assert (node.source_id, node.map.map_id) == ("N1", "lif-example-02:Map_Z-Level_1")
    assert Node.objects.get(node_id="N1").source_id == ""
    assert set(load_site_graph(site=Site.objects.get()).nodes) == {
        "N1",
        "N2",
        "lif-example-02:N1",
        "lif-example-02:N2",
    }
    assert VehicleType.objects.filter(type_id="Vehicle_Type_1").count() == 1  # types are shared


def test_a_project_imported_before_needs_replace_and_replace_swaps_it() -> None:
    first = import_lif(source=example("10.6_"), site_id="plant")
    updated = example("10.6_")
    updated["layouts"][0]["nodes"][0]["nodePosition"]["x"] = -1.0

    refused = import_lif(source=updated, site_id="plant")
    replaced = import_lif(source=updated, site_id="plant", replace=True)

    assert "already imported" in str(refused.errors[0])
    assert replaced.ok
    assert replaced.prefix == ""
    assert Node.objects.get(node_id="N1").x == -1.0
    assert LifImport.objects.get().pk == replaced.import_pk != first.import_pk


def test_the_import_record_keeps_meta_information_and_report() -> None:
    report = import_lif(source=example("10.5_"), site_id="plant", file_name="ex5.json")

    record = LifImport.objects.get(pk=report.import_pk)

    assert (record.project, record.creator, record.lif_version) == (
        "LIF Example 05",
        "VDMA",
        "0.11.0",
    )
    assert record.file_name == "ex5.json"
    assert record.report["counts"] == {
        "maps": 2,
        "layouts": 2,
        "nodes": 4,
        "edges": 2,
        "stations": 0,
        "vehicle types": 1,
    }


def test_demo_layout_exports_with_kinds_and_re_imports(demo_map) -> None:
    exported = export_map_lif(map=demo_map)
    Station.objects.filter(map=demo_map).delete()
    demo_map.delete()

    report = import_lif(source=exported, site_id="demo-site")

    assert report.ok, report.lines()
    assert sorted(set(Station.objects.values_list("kind", flat=True))) == [
        "CHARGE",
        "DROP",
        "PARK",
        "PICK",
    ]
    assert not VehicleType.objects.exists()
    assert "open to every vehicle" in str(report.warnings[0])


@pytest.mark.parametrize("body", [True, 12, [{"layouts": []}]])
def test_a_json_body_that_is_not_an_object_is_reported_not_a_server_error(body) -> None:
    """Found by the API fuzzer: `true` as the request body reached json.loads and raised."""
    document, report = parse_lif(body)
    assert document is None
    assert report.errors
    assert "JSON object" in str(report.as_dict())
