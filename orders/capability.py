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
    return _positive(physical.get("heightMax")) if isinstance(physical, Mapping) else None


def with_height(profile: VehicleProfile, factsheet: Factsheet) -> VehicleProfile:
    """`profile` (of the vehicle's type) raised to the factsheet's heightMax where that is
    higher, so routes keep under the edges' maxHeight (REFERENCE J.43)."""
    height = height_max(factsheet)
    if height is None or (profile.height is not None and profile.height >= height):
        return profile
    return replace(profile, height=height)


def _positive(value: Any) -> float | None:
    if isinstance(value, int | float) and not isinstance(value, bool) and value > 0:
        return float(value)
    return None


def _load_set(factsheet: Factsheet, load_type: str) -> Mapping[str, Any] | None:
    sets = ((factsheet or {}).get("loadSpecification") or {}).get("loadSets") or []
    return next(
        (
            s
            for s in sets
            if isinstance(s, Mapping) and load_type and s.get("loadType") == load_type
        ),
        None,
    )


def max_load_mass(factsheet: Factsheet, load_type: str = "") -> float | None:
    """The heaviest load (kg) the vehicle takes: `typeSpecification.maxLoadMass`, lowered by the
    `maxWeight` of the load set for `load_type` (REFERENCE J.42, J.46); None when unstated."""
    limits = [_positive(((factsheet or {}).get("typeSpecification") or {}).get("maxLoadMass"))]
    load_set = _load_set(factsheet, load_type)
    if load_set is not None:
        limits.append(_positive(load_set.get("maxWeight")))
    stated = [limit for limit in limits if limit is not None]
    return min(stated) if stated else None


def loaded_speed(factsheet: Factsheet, load_type: str) -> float | None:
    """The speed (m/s) allowed with a load of `load_type` on board: the `agvSpeedLimit` of the
    factsheet's load set for that type (REFERENCE J.46), or None."""
    load_set = _load_set(factsheet, load_type)
    return None if load_set is None else _positive(load_set.get("agvSpeedLimit"))


def critical_charge(factsheet: Factsheet) -> float | None:
    """The battery level (%) below which the vehicle takes only charging orders: 3.0
    `batteryCharging.criticalLowChargingLevel`, which control keeps under `vehicleConfig`."""
    config = (factsheet or {}).get("vehicleConfig") or {}
    charging = config.get("batteryCharging") if isinstance(config, Mapping) else None
    if not isinstance(charging, Mapping):
        return None
    return _positive(charging.get("criticalLowChargingLevel"))


def loaded(profile: VehicleProfile | None, factsheet: Factsheet, load_type: str) -> VehicleProfile:
    """The profile for legs with a load on board: LIF `loadRestriction` (loaded) and
    `loadSetNames` (the factsheet's load set for `load_type`, if it names one) apply."""
    load_set = _load_set(factsheet, load_type)
    name = str(load_set["setName"]) if load_set is not None and load_set.get("setName") else None
    return replace(profile or VehicleProfile(), loaded=True, load_set=name)


def refusal(
    factsheet: Factsheet,
    *,
    load_type: str,
    actions: Iterable[str],
    load_weight: float | None = None,
) -> str | None:
    """Why the vehicle cannot do an order with `load_type` (of `load_weight` kg, if known) and
    node `actions`, or None."""
    loads = load_types(factsheet)
    if load_type and loads is not None and load_type not in loads:
        return f"load type {load_type}"
    limit = max_load_mass(factsheet, load_type)
    if load_weight is not None and limit is not None and load_weight > limit:
        return f"a load of {load_weight:g} kg (at most {limit:g} kg)"
    declared = node_actions(factsheet)
    if declared is not None:
        missing = sorted(set(actions) - declared)
        if missing:
            return f"action {', '.join(missing)}"
    return None
