"""What a vehicle can do for a transport order, read from its factsheet (a camelCase dict as
`control` stores it). Framework-free so dispatch, the API and the benchmark share it.

A factsheet that says nothing about a point (no load sets, no declared actions) does not
exclude the vehicle: many deployed stacks leave them out, and the vehicle still rejects what it
cannot do.
"""

from collections.abc import Iterable, Mapping
from dataclasses import replace
from typing import Any

from traffic import VehicleProfile

Factsheet = Mapping[str, Any] | None


def load_types(factsheet: Factsheet) -> set[str] | None:
    """The load types the vehicle declares (`loadSpecification.loadSets[].loadType`), or None
    when it declares none."""
    sets = ((factsheet or {}).get("loadSpecification") or {}).get("loadSets") or []
    types = {str(s["loadType"]) for s in sets if isinstance(s, Mapping) and s.get("loadType")}
    return types or None


def node_actions(factsheet: Factsheet) -> set[str] | None:
    """Action types the vehicle declares for the NODE scope, or None when it declares none."""
    actions = ((factsheet or {}).get("protocolFeatures") or {}).get("agvActions") or []
    declared = {
        str(a["actionType"])
        for a in actions
        if isinstance(a, Mapping)
        and a.get("actionType")
        and "NODE" in (a.get("actionScopes") or [])
    }
    return declared or None


def series_name(factsheet: Factsheet) -> str:
    """The vehicle's series (`typeSpecification.seriesName`), or ""."""
    return str(((factsheet or {}).get("typeSpecification") or {}).get("seriesName") or "")


def height_max(factsheet: Factsheet) -> float | None:
    """The vehicle's highest point (`physicalParameters.heightMax`, m), or None."""
    physical = (factsheet or {}).get("physicalParameters") or {}
    height = physical.get("heightMax") if isinstance(physical, Mapping) else None
    if isinstance(height, int | float) and not isinstance(height, bool) and height > 0:
        return float(height)
    return None


def with_height(profile: VehicleProfile, factsheet: Factsheet) -> VehicleProfile:
    """`profile` (of the vehicle's type) raised to the factsheet's heightMax where that is
    higher, so routes keep under the edges' maxHeight (REFERENCE J.43)."""
    height = height_max(factsheet)
    if height is None or (profile.height is not None and profile.height >= height):
        return profile
    return replace(profile, height=height)


def refusal(factsheet: Factsheet, *, load_type: str, actions: Iterable[str]) -> str | None:
    """Why the vehicle cannot do an order with `load_type` and node `actions`, or None."""
    loads = load_types(factsheet)
    if load_type and loads is not None and load_type not in loads:
        return f"load type {load_type}"
    declared = node_actions(factsheet)
    if declared is not None:
        missing = sorted(set(actions) - declared)
        if missing:
            return f"action {', '.join(missing)}"
    return None
