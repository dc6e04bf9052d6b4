"""Prepares the benchmark database (run as a process with Django configured).

A warehouse grid with a park spur at every aisle node (each vehicle's home, off the aisles),
pick stations along the top row and drop stations along the bottom row, and with `--shelves`
a handover spur (a shelf, pick and drop) at every aisle node too; a logged-in session for the
websocket client and an ERP token for the API client.

    DATABASE_URL=... python -m bench.load.setup --vehicles 1000 --out DIR [--shelves]
"""

import argparse
import inspect
import json
import math
import os
from pathlib import Path
from typing import Any

SPACING = 6.0  # m between aisle nodes: a parked vehicle is 2 m clear of both aisles
SPUR = 2.0


def layout_spec(vehicles: int, shelves: bool = False) -> dict[str, Any]:
    """Layout data for `maps.services.create_layout` with at least `vehicles` park spurs.

    Park spurs leave an aisle node up and right, shelves (`shelves`) up and left: 2 m from
    the next column's park spur, clear of a 1.2 × 0.8 m vehicle with its load."""
    columns = max(4, math.ceil(math.sqrt(vehicles * 1.6)))
    rows = max(3, math.ceil(vehicles / columns))
    nodes: list[dict[str, Any]] = []
    edges: list[dict[str, Any]] = []
    stations: list[dict[str, Any]] = []

    def two_way(a: str, b: str) -> None:
        edges.append({"id": f"{a}-{b}", "start": a, "end": b})
        edges.append({"id": f"{b}-{a}", "start": b, "end": a})

    def spur(kind: str, station_id: str, aisle: str, x: float, y: float) -> None:
        node_id = f"S-{station_id}"
        nodes.append({"id": node_id, "x": x, "y": y})
        two_way(aisle, node_id)
        stations.append({"id": station_id, "name": station_id, "kind": kind, "node": node_id})

    for c in range(columns):
        for r in range(rows):
            nodes.append({"id": f"A{c}.{r}", "x": c * SPACING, "y": r * SPACING})
            if c:
                two_way(f"A{c - 1}.{r}", f"A{c}.{r}")
            if r:
                two_way(f"A{c}.{r - 1}", f"A{c}.{r}")
    for c in range(columns):
        x = c * SPACING
        spur("PICK", f"PICK-{c:03d}", f"A{c}.{rows - 1}", x, (rows - 1) * SPACING + SPUR)
        spur("DROP", f"DROP-{c:03d}", f"A{c}.0", x, -SPUR)
        for r in range(rows):
            spur("PARK", f"PARK-{c:03d}-{r:03d}", f"A{c}.{r}", x + SPUR, r * SPACING + SPUR)
            if shelves:
                y = r * SPACING + SPUR
                spur("HANDOVER", f"SHELF-{c:03d}-{r:03d}", f"A{c}.{r}", x - SPUR, y)
    return {
        "mapId": "load",
        "name": "Load benchmark",
        "nodes": nodes,
        "edges": edges,
        "stations": stations,
    }


def prepare(vehicles: int, out: Path, shelves: bool = False) -> dict[str, Any]:
    """Create layout, user session and ERP token; write the simulator's layout file."""
    from django.contrib.auth import (
        BACKEND_SESSION_KEY,
        HASH_SESSION_KEY,
        SESSION_KEY,
        get_user_model,
    )
    from django.contrib.sessions.backends.db import SessionStore

    from maps.selectors import layout_as_dict
    from maps.services import create_layout
    from orders import services

    layout = create_layout(spec=layout_spec(vehicles, shelves), replace=True)
    data = layout_as_dict(map=layout)
    (out / "layout.json").write_text(json.dumps(data))
    user = get_user_model().objects.create_superuser("loadbench", "", None)
    session = SessionStore()
    session[SESSION_KEY] = str(user.pk)
    session[BACKEND_SESSION_KEY] = "django.contrib.auth.backends.ModelBackend"
    session[HASH_SESSION_KEY] = user.get_session_auth_hash()
    session.create()
    scoped = "scopes" in inspect.signature(services.create_integration_client).parameters
    extra: dict[str, Any] = {"scopes": ["orders:read", "orders:write"]} if scoped else {}
    client = services.create_integration_client(name="loadbench", **extra)
    token = services.issue_api_token(client=client)[1]
    info = {
        "session": session.session_key,
        "token": token,
        "stations": len(data["stations"]),
        "nodes": len(data["nodes"]),
    }
    (out / "setup.json").write_text(json.dumps(info))
    return info


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--vehicles", type=int, required=True)
    parser.add_argument("--out", type=Path, required=True)
    parser.add_argument("--shelves", action="store_true", help="a shelf at every aisle node")
    args = parser.parse_args()
    os.environ.setdefault("DJANGO_SETTINGS_MODULE", "fleet.settings")
    import django

    django.setup()
    print(json.dumps(prepare(args.vehicles, args.out, args.shelves)))


if __name__ == "__main__":
    main()
