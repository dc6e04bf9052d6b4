"""The shortlist of a dispatch cycle: the few idle vehicles nearest to its orders (issue 11).

A cycle with one new order used to read, check and price every idle vehicle of the fleet: the
rows, factsheets, battery and maintenance holds and capabilities of a thousand vehicles, ~0.25 s
of its ~0.3 s. Only the nearest few can win, though. So when a handful of orders wait and many
vehicles stand idle, a cycle first ranks the vehicles by travel time to each order's first
stop from a light read (id, map, node of every vehicle that may be idle) and checks only the
nearest `SPARE` more than there are orders (plus any vehicle an order is bound to).

Accepting the shortlist's plan is safe only when it is the plan of the whole fleet. It is when
every order is served and each order either is bound to one vehicle (its intended vehicle or its
sequence's) or has at least as many vehicles able to take it in its own shortlist as the map
has orders: an optimal assignment then exists among those (were an order given a farther
vehicle, one of its nearer ones is left free, and swapping does not cost more), so the solver
finds the same pairs. Otherwise the cycle runs on the whole fleet as before. The one difference:
between vehicles within a second of each other, longest-idle-first is ranked among the
shortlist, not the fleet (an exact tie still goes to the vehicle idle the longest).

Travel times are the layout's default ones, so the shortlist applies only on sites without
vehicle types (typed vehicles have their own speeds and rules: their cycle uses the whole fleet).
"""

import heapq
from dataclasses import dataclass, field
from datetime import datetime

from django.db.models import Exists, OuterRef, Q

from maps.models import VehicleType
from maps.selectors import load_graph
from orders import selectors
from orders.assignment import Candidate, DistancesTo, Job
from orders.models import TransportOrder
from orders.services.dispatch_factsheets import Digest, factsheet_digest
from orders.services.fit import order_steps
from robots.models import Vehicle
from traffic import NoRouteError, RoutingGraph

SPARE = 8  # vehicles checked per order beyond the number of orders (held, refused, …)
MAX_ORDERS = 16  # a larger batch (a backlog) is priced against the whole fleet
_WORTH_IT = 3  # the shortlist must be this many times smaller than the fleet


@dataclass
class Shortlist:
    """The idle vehicles of a cycle's shortlist, and per order the vehicles nearest to it."""

    idle: list[Vehicle]
    nearest: dict[int, frozenset[int]] = field(default_factory=dict)  # order pk -> vehicle pks
    bound: set[int] = field(default_factory=set)  # orders only one known vehicle may take
    graphs: dict[int, RoutingGraph] = field(default_factory=dict)  # map pk -> graph it used
    digests: dict[int, Digest] = field(default_factory=dict)  # vehicle pk -> factsheet's

    def covers(
        self,
        orders: list[TransportOrder],
        jobs: list[Job],
        candidates: list[Candidate],
        travel_times_to: DistancesTo,
    ) -> bool:
        """Whether the plan over `candidates` (the shortlist's, on one map) is the plan over
        the whole fleet: see the module's docstring."""
        if len(jobs) != len(orders):
            return False  # an order waits for a reason that may not hold for the whole fleet
        for job in jobs:
            if job.key in self.bound:
                continue
            table = travel_times_to(job.pickup)
            able = sum(
                1
                for c in candidates
                if c.key in self.nearest.get(job.key, ())
                and (job.allowed is None or c.key in job.allowed)
                and c.node in table
            )
            if able < len(jobs):
                return False
        return True


def shortlist(
    *,
    orders: list[TransportOrder],
    held_since: datetime,
    gate: selectors.SequenceGate,
    types: list[VehicleType],
) -> Shortlist | None:
    """The shortlist for `orders` (ready to assign), or None when the whole fleet should be
    priced: many orders, few vehicles, vehicle types on the site (`types`), or no vehicle in
    reach."""
    if not orders or len(orders) > MAX_ORDERS or types:
        return None
    positions = _possibly_idle()
    wanted: set[int] = set()
    found = Shortlist(idle=[])
    graphs = found.graphs
    for order in orders:
        bound = gate.vehicle_of.get(order.sequence_id or 0) or order.intended_vehicle_id
        if bound is not None:
            wanted.add(bound)
            found.bound.add(order.pk)
            continue
        layout = order.source.map
        graph = graphs.get(layout.pk)
        if graph is None:
            graph = graphs[layout.pk] = load_graph(map=layout)
        nearest = _nearest(order, graph, positions, len(orders) + SPARE)
        if nearest is None:
            return None
        found.nearest[order.pk] = nearest
        wanted |= nearest
    if not wanted or len(wanted) * _WORTH_IT > len(positions):
        return None
    found.idle, found.digests = _idle(wanted, held_since)
    return found


def _possibly_idle() -> dict[int, tuple[str, str]]:
    """Vehicle pk -> (map id, node) of every vehicle that may be idle: online, in an automatic
    mode, not paused, positioned, without an active order. A superset of the idle ones (fatal
    errors and holds are checked on the shortlist), in one light query."""
    busy = TransportOrder.objects.filter(
        status__in=TransportOrder.ACTIVE_STATUSES, vehicle__isnull=False
    ).values("vehicle_id")
    rows = (
        Vehicle.objects.filter(
            connection=Vehicle.Connection.ONLINE,
            operating_mode__in=["AUTOMATIC", "SEMIAUTOMATIC"],
            paused=False,
        )
        .exclude(Q(last_node_id="") | Q(pk__in=busy))
        .values_list("pk", "map_id", "last_node_id")
    )
    return {pk: (map_id, node) for pk, map_id, node in rows}


def _nearest(
    order: TransportOrder, graph: RoutingGraph, positions: dict[int, tuple[str, str]], count: int
) -> frozenset[int] | None:
    """The `count` vehicles nearest (travel time) to the order's first stop, with every vehicle
    as near as the last of them; None when its layout cannot price the stop."""
    try:
        table = graph.travel_times_to(order_steps(order)[0].station.node.node_id)
    except NoRouteError:
        return None
    map_id = order.source.map.map_id
    times = [
        (seconds, pk)
        for pk, (on_map, node) in positions.items()
        if on_map == map_id and (seconds := table.get(node)) is not None
    ]
    nearest = heapq.nsmallest(count, times)
    if not nearest:
        return None
    last = nearest[-1][0]  # vehicles tied with the last one are in too
    return frozenset(pk for seconds, pk in times if seconds <= last)


def _idle(pks: set[int], held_since: datetime) -> tuple[list[Vehicle], dict[int, Digest]]:
    """The vehicles of `pks` that are idle as `selectors.get_dispatch_fleet` has it (online,
    available, not held by a command since `held_since`, no active order), read afresh, and
    their factsheets' fingerprints (`attach_factsheets`): the held ones in one query, the
    rest in another."""
    held = selectors.list_held_vehicles(since=held_since)
    busy = TransportOrder.objects.filter(
        status__in=TransportOrder.ACTIVE_STATUSES, vehicle_id=OuterRef("pk")
    )
    rows = (
        Vehicle.objects.filter(pk__in=pks, connection=Vehicle.Connection.ONLINE)
        .exclude(Exists(busy))
        .defer("factsheet")
        .annotate(factsheet_digest=factsheet_digest())
        .order_by("pk")
    )
    idle = [v for v in rows if v.is_available and v.pk not in held]
    return list[Vehicle](idle), {v.pk: v.factsheet_digest for v in idle}
