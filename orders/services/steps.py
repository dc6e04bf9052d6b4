"""The steps of a transport order: what a caller asks for and the checks before it is stored.

A step is a station and what to do there (pick, drop or a custom VDA 5050 action with its
parameters). Consecutive steps must be reachable one from the next on the map, for the order's
vehicle type when it has one (routing applies that type's node and edge restrictions).
"""

from dataclasses import dataclass, field
from typing import Any

from fleet.exceptions import InvalidRequestError
from maps.models import Map, Station, VehicleType
from maps.selectors import load_graph, vehicle_profile
from orders.models import OrderStep
from robots.models import Vehicle
from traffic import NoRouteError

Operation = OrderStep.Operation
MAX_STEPS = 50
# Parameters control sets on pick and drop itself; a step may not override them.
_RESERVED = {"stationName", "stationType"}


@dataclass(frozen=True)
class StepSpec:
    """One requested step (validated by `check_steps`)."""

    station: Station
    operation: str = Operation.PICK
    action_type: str = ""
    parameters: dict[str, Any] = field(default_factory=dict)

    @property
    def vda_action_type(self) -> str:
        return self.action_type if self.operation == Operation.ACTION else self.operation.lower()


def pick_drop(source: Station, destination: Station) -> list[StepSpec]:
    """The two steps of a classic transport order."""
    return [StepSpec(source, Operation.PICK), StepSpec(destination, Operation.DROP)]


def check_steps(
    steps: list[StepSpec],
    *,
    vehicle_type: VehicleType | None = None,
    intended_vehicle: Vehicle | None = None,
) -> None:
    """Raise InvalidRequestError naming the first step that cannot be done, and why."""
    if not steps:
        raise InvalidRequestError("an order needs at least one step")
    if len(steps) > MAX_STEPS:
        raise InvalidRequestError(f"an order has at most {MAX_STEPS} steps")
    layout = steps[0].station.map
    for number, step in enumerate(steps, start=1):
        _check_step(number, step, layout.pk)
    if intended_vehicle is not None and intended_vehicle.map_id not in ("", layout.map_id):
        raise InvalidRequestError(
            f"vehicle {intended_vehicle.serial_number} is on map {intended_vehicle.map_id}, "
            f"the steps on {layout.map_id}"
        )
    graph = load_graph(map=layout)
    profile = vehicle_profile(vehicle_type=vehicle_type)
    who = f" for vehicle type {vehicle_type.type_id}" if vehicle_type else ""
    for number, (before, after) in enumerate(zip(steps, steps[1:], strict=False), start=2):
        start, goal = before.station.node.node_id, after.station.node.node_id
        try:
            graph.route_from_table(start, goal, vehicle=profile)
        except NoRouteError:
            raise InvalidRequestError(
                f"step {number} ({after.station.station_id}) cannot be reached from step "
                f"{number - 1} ({before.station.station_id}){who}"
            ) from None


def _check_step(number: int, step: StepSpec, map_pk: int) -> None:
    name = f"step {number} ({step.station.station_id})"
    if step.station.map_id != map_pk:
        raise InvalidRequestError(f"{name} is on another map than step 1")
    if step.operation not in Operation.values:
        raise InvalidRequestError(f"{name}: unknown operation {step.operation!r}")
    if step.operation == Operation.ACTION and not step.action_type:
        raise InvalidRequestError(f"{name}: a custom action needs an action_type")
    if step.operation != Operation.ACTION and step.action_type:
        raise InvalidRequestError(f"{name}: action_type is only for operation ACTION")
    if not isinstance(step.parameters, dict):
        raise InvalidRequestError(f"{name}: parameters must be an object")
    reserved = sorted(_RESERVED & step.parameters.keys())
    if reserved and step.operation != Operation.ACTION:
        raise InvalidRequestError(f"{name}: parameters {', '.join(reserved)} are set by the system")


def save_steps(order_pk: int, steps: list[StepSpec]) -> list[OrderStep]:
    """Store the checked steps of a new order."""
    return OrderStep.objects.bulk_create(
        OrderStep(
            order_id=order_pk,
            index=index,
            station=step.station,
            operation=step.operation,
            action_type=step.action_type if step.operation == Operation.ACTION else "",
            parameters=step.parameters,
        )
        for index, step in enumerate(steps)
    )


def parse_steps(layout: Map, items: Any) -> list[StepSpec]:
    """Steps as JSON (`[{"station", "operation", "action_type", "parameters"}, …]`, stations by
    id on `layout`) for recurring orders and forms; InvalidRequestError names what is wrong."""
    if not isinstance(items, list) or not items:
        raise InvalidRequestError("steps must be a non-empty list")
    stations = {s.station_id: s for s in Station.objects.filter(map=layout).select_related("node")}
    steps = []
    for number, item in enumerate(items, start=1):
        if not isinstance(item, dict):
            raise InvalidRequestError(f"step {number} must be an object")
        station = stations.get(str(item.get("station", "")))
        if station is None:
            raise InvalidRequestError(
                f"step {number}: no station {item.get('station')!r} on map {layout.map_id}"
            )
        steps.append(
            StepSpec(
                station=station,
                operation=str(item.get("operation", "")).upper(),
                action_type=str(item.get("action_type") or ""),
                parameters=item.get("parameters") or {},
            )
        )
    return steps
