"""Which vehicles fit an order, and the route through its steps (used by each dispatch cycle).

Capability checks come from the factsheets (`orders.capability`), load weights from the
inventory; the route takes the order's steps in turn, loaded between a pick and its drop.
"""

from maps.models import VehicleType
from orders import capability, selectors
from orders.models import OrderStep, TransportOrder
from robots.models import Vehicle
from traffic import NoRouteError, RoutingGraph, VehicleProfile


def order_steps(order: TransportOrder) -> list[OrderStep]:
    """The order's steps (prefetched); an order saved without steps is its pick → drop pair."""
    steps = list(order.steps.all())
    if steps:
        return steps
    cached: list[OrderStep] | None = getattr(order, "_pick_drop", None)
    if cached is None:
        cached = [
            OrderStep(index=0, station=order.source, operation=OrderStep.Operation.PICK),
            OrderStep(index=1, station=order.destination, operation=OrderStep.Operation.DROP),
        ]
        order._pick_drop = cached  # type: ignore[attr-defined]
    return cached


def allowed_vehicles(
    order: TransportOrder,
    vehicles: list[Vehicle],
    types: dict[int, VehicleType],
    gate: selectors.SequenceGate,
    capabilities: "Capabilities",
) -> tuple[frozenset[int] | None, str | None]:
    """The idle vehicles that may take `order` (None: any), or why none may now."""
    idle = capabilities.idle
    bound = gate.vehicle_of.get(order.sequence_id) if order.sequence_id else None
    if bound is not None:
        if bound not in idle:
            return None, "waits for the vehicle of its sequence to be free"
        allowed = {bound}
    elif order.intended_vehicle_id is not None:
        if order.intended_vehicle_id not in idle:
            return None, f"waits for its intended vehicle {order.intended_vehicle} to be free"
        allowed = {order.intended_vehicle_id}
    else:
        allowed = idle
    # A vehicle bound to a sequence with open orders takes no other work.
    others = {pk for pk, sequence in gate.reserved.items() if sequence != order.sequence_id}
    if allowed & others:
        allowed = allowed - others
        if not allowed:
            return None, "the idle vehicles are reserved for order sequences"
    if order.vehicle_type_id is not None:
        allowed = {pk for pk in allowed if pk in types and types[pk].pk == order.vehicle_type_id}
        if not allowed:
            return None, f"no idle vehicle of type {order.vehicle_type}"
    actions = frozenset(step.vda_action_type for step in order_steps(order))
    refusals = {
        pk: reason
        for pk, reason in capabilities.refusals(order.load_type, actions, order.load_id).items()
        if pk in allowed
    }
    if refusals.keys() == allowed:
        reason = sorted(set(refusals.values()))[0]
        return None, f"no idle vehicle can handle {reason}"
    if refusals or allowed != idle:
        return frozenset(allowed - refusals.keys()), None
    return None, None


class Capabilities:
    """Which vehicles refuse which (load type, step actions), from their factsheets: read once
    per cycle and cached per distinct question (a backlog asks the same few many times)."""

    def __init__(self, vehicles: list[Vehicle], weights: dict[str, float] | None = None) -> None:
        # Only vehicles whose factsheet declares load sets, node actions or a load limit can
        # refuse anything.
        self._factsheets = {
            v.pk: v.factsheet
            for v in vehicles
            if capability.load_types(v.factsheet) is not None
            or capability.node_actions(v.factsheet) is not None
            or capability.max_load_mass(v.factsheet) is not None
        }
        self._weights = weights or {}
        self._cache: dict[tuple[str, frozenset[str], float | None], dict[int, str]] = {}
        self.idle = {v.pk for v in vehicles}

    def refusals(
        self, load_type: str, actions: frozenset[str], load_id: str = ""
    ) -> dict[int, str]:
        """Vehicle pk -> what it cannot handle (the load's weight from the inventory counts)."""
        weight = self._weights.get(load_id) if load_id else None
        key = (load_type, actions, weight)
        found = self._cache.get(key)
        if found is None:
            found = {}
            for pk, factsheet in self._factsheets.items():
                reason = capability.refusal(
                    factsheet, load_type=load_type, actions=actions, load_weight=weight
                )
                if reason is not None:
                    found[pk] = reason
            self._cache[key] = found
        return found


def route_through_steps(
    graph: RoutingGraph,
    vehicle: Vehicle,
    steps: list[OrderStep],
    profile: VehicleProfile | None,
    loaded: VehicleProfile | None = None,
) -> tuple[list[str], list[int]] | str:
    """The quickest route from the vehicle through every step's node, with each step's index in
    it; or why there is none. Legs after a pick and before the next drop are planned with the
    `loaded` profile (LIF load restrictions and load sets, REFERENCE J.46)."""
    route, indices, carrying = [vehicle.last_node_id], [], False
    for number, step in enumerate(steps, start=1):
        goal = step.station.node.node_id
        leg_profile = loaded if carrying and loaded is not None else profile
        try:
            leg = graph.route_from_table(route[-1], goal, vehicle=leg_profile).nodes
        except NoRouteError:
            return f"step {number} ({step.station.station_id}) cannot be reached by {vehicle}"
        route += leg[1:]
        indices.append(len(route) - 1)
        if step.operation == OrderStep.Operation.PICK:
            carrying = True
        elif step.operation == OrderStep.Operation.DROP:
            carrying = False
    return route, indices
