"""The demo warehouse: a grid of aisles with pick, drop, charge and park stations on spurs.

Stations sit on short dead-end spurs off the aisles, so a vehicle working at a station does not
stand in a through aisle.
"""

from typing import Any

SPACING = 3.0  # metres between aisle nodes
SPUR = 2.0  # metres from an aisle node to its station node


def warehouse_layout(*, columns: int = 8, rows: int = 5, map_id: str = "demo") -> dict[str, Any]:
    """Layout data for `maps.services.create_layout`: a `columns` × `rows` aisle grid."""
    nodes: list[dict[str, Any]] = []
    edges: list[dict[str, Any]] = []
    stations: list[dict[str, Any]] = []

    def node(node_id: str, x: float, y: float) -> None:
        nodes.append({"id": node_id, "x": x, "y": y})

    def two_way(a: str, b: str) -> None:
        edges.append({"id": f"{a}-{b}", "start": a, "end": b})
        edges.append({"id": f"{b}-{a}", "start": b, "end": a})

    for c in range(columns):
        for r in range(rows):
            node(f"A{c}.{r}", c * SPACING, r * SPACING)
            if c:
                two_way(f"A{c - 1}.{r}", f"A{c}.{r}")
            if r:
                two_way(f"A{c}.{r - 1}", f"A{c}.{r}")

    def spur(kind: str, station_id: str, aisle: str, dx: float, dy: float) -> None:
        aisle_node = next(n for n in nodes if n["id"] == aisle)
        node_id = f"S-{station_id}"
        node(node_id, aisle_node["x"] + dx, aisle_node["y"] + dy)
        two_way(aisle, node_id)
        stations.append({"id": station_id, "name": station_id, "kind": kind, "node": node_id})

    top = rows - 1
    for c in range(1, columns - 1):
        spur("PICK", f"PICK-{c}", f"A{c}.{top}", 0.0, SPUR)
        spur("DROP", f"DROP-{c}", f"A{c}.0", 0.0, -SPUR)
    for r in range(rows):
        spur("PARK", f"PARK-{r + 1}", f"A0.{r}", -SPUR, 0.0)
    for r in (1, 3):
        if r < rows:
            spur("CHARGE", f"CHARGE-{r // 2 + 1}", f"A{columns - 1}.{r}", SPUR, 0.0)
    return {
        "mapId": map_id,
        "name": "Demo warehouse",
        "nodes": nodes,
        "edges": edges,
        "stations": stations,
    }
