"""Which idle vehicle takes which pending order: a batch assignment, framework-free.

Dispatch (`orders.services.dispatch`) turns rows into `Job`s and `Candidate`s, and the benchmark
builds them in memory. `plan_batch` solves one assignment problem per cycle with
`scipy.optimize.linear_sum_assignment` over the routing distance from each vehicle to each
order's pickup; `plan_greedy` is the nearest-vehicle loop it replaced, kept as the baseline.

Rules of the batch:
- Only as many orders as there are idle vehicles enter a cycle, most urgent first (priority,
  then deadline, then age). An order no idle vehicle can reach does not take a place.
- Distances are weighted by urgency, so in a contest for a near vehicle the more urgent order
  wins: weight 1 + the order's rank among the distinct priorities of the batch, doubled when
  its deadline is near or past.
- Ties between vehicles at the same distance go to the one idle the longest (fairness).
"""

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from datetime import datetime, timedelta

import numpy as np
from scipy.optimize import linear_sum_assignment

DUE_SOON = timedelta(minutes=15)  # a deadline this close makes an order count double
_TIE_BREAK = 1e-3  # metres per rank of idle time: decides between vehicles within ~0.2 m

DistancesTo = Callable[[str], dict[str, float]]


@dataclass(frozen=True)
class Job:
    """A pending order as dispatch sees it."""

    key: int
    pickup: str  # node id of the source station
    station: str  # station id, for the notes
    priority: int = 0
    deadline: datetime | None = None
    created: datetime | None = None


@dataclass(frozen=True)
class Candidate:
    """An idle vehicle: where it stands and since when it has had nothing to do."""

    key: int
    node: str
    idle_since: datetime | None = None  # None: never had an order, the longest idle of all


@dataclass
class Plan:
    """Pairs to assign with their empty-travel distance, and why each other job waits."""

    pairs: list[tuple[Job, Candidate, float]] = field(default_factory=list)
    notes: dict[int, str] = field(default_factory=dict)

    @property
    def empty_travel(self) -> float:
        """Total distance the vehicles drive empty to their pickups."""
        return sum(distance for _, _, distance in self.pairs)


def urgency_key(job: Job) -> tuple[int, float, float, int]:
    """Sort key: higher priority, then earlier deadline (none last), then older, then lower id."""
    return (
        -job.priority,
        _timestamp(job.deadline, math.inf),
        _timestamp(job.created, 0.0),
        job.key,
    )


def plan_batch(
    jobs: Sequence[Job],
    candidates: Sequence[Candidate],
    distances_to: DistancesTo,
    *,
    now: datetime | None = None,
) -> Plan:
    """Assign up to len(candidates) of the most urgent reachable jobs at least weighted cost."""
    plan, reachable, distances = _triage(jobs, candidates, distances_to)
    free = _by_idle_time(candidates)
    waiting, unserved = reachable, []
    while waiting and free:
        # A job the solver leaves out cannot reach any vehicle still free (serving it would
        # always be cheaper), so it waits for the next cycle; the next jobs get a chance.
        batch, waiting = waiting[: len(free)], waiting[len(free) :]
        assigned = _solve(batch, free, distances, now)
        plan.pairs.extend(assigned)
        served = {job.key for job, _, _ in assigned}
        taken = {vehicle.key for _, vehicle, _ in assigned}
        unserved += [job for job in batch if job.key not in served]
        free = [vehicle for vehicle in free if vehicle.key not in taken]
    for job in unserved + waiting:
        plan.notes[job.key] = _waiting_note(job, candidates, distances)
    return plan


def plan_greedy(
    jobs: Sequence[Job], candidates: Sequence[Candidate], distances_to: DistancesTo
) -> Plan:
    """The baseline: in urgency order, each job takes the nearest free vehicle."""
    plan, reachable, distances = _triage(jobs, candidates, distances_to)
    free = list(candidates)
    for job in reachable:
        distance = distances[job.pickup]
        options = [v for v in free if v.node in distance]
        if not options:
            plan.notes[job.key] = _waiting_note(job, candidates, distances)
            continue
        vehicle = min(options, key=lambda v: (distance[v.node], v.key))
        plan.pairs.append((job, vehicle, distance[vehicle.node]))
        free.remove(vehicle)
    return plan


def _triage(
    jobs: Sequence[Job], candidates: Sequence[Candidate], distances_to: DistancesTo
) -> tuple[Plan, list[Job], dict[str, dict[str, float]]]:
    """Sort by urgency, note the jobs no idle vehicle can reach, and cache distances per pickup."""
    plan = Plan()
    distances: dict[str, dict[str, float]] = {}
    reachable: list[Job] = []
    nodes = {vehicle.node for vehicle in candidates}
    for job in sorted(jobs, key=urgency_key):
        if job.pickup not in distances:
            distances[job.pickup] = distances_to(job.pickup)
        if nodes & distances[job.pickup].keys():
            reachable.append(job)
        elif candidates:
            plan.notes[job.key] = f"no vehicle can reach {job.station}"
        else:
            plan.notes[job.key] = "no vehicle available"
    return plan, reachable, distances


def _solve(
    jobs: list[Job],
    vehicles: list[Candidate],
    distances: dict[str, dict[str, float]],
    now: datetime | None,
) -> list[tuple[Job, Candidate, float]]:
    """One assignment problem. Besides the vehicles, each job (sorted by urgency) may take a
    column of its own meaning "not served this time", at a price that grows with its urgency in
    steps larger than any sum of travel costs: so the most urgent jobs are served first, and
    only among equally served sets does travel decide."""
    raw = np.full((len(jobs), len(vehicles)), np.inf)
    for row, job in enumerate(jobs):
        distance = distances[job.pickup]
        for column, vehicle in enumerate(vehicles):
            if vehicle.node in distance:
                raw[row, column] = distance[vehicle.node]
    cost = raw * _urgency_weights(jobs, now)[:, None]
    cost += np.arange(len(vehicles))[None, :] * _TIE_BREAK  # vehicles are sorted by idle time
    finite = cost[np.isfinite(cost)]
    if not finite.size:
        return []
    step = float(finite.max()) * len(jobs) + 1.0
    unserved = np.full((len(jobs), len(jobs)), np.inf)
    np.fill_diagonal(unserved, step * (len(jobs) - np.arange(len(jobs))))
    rows, columns = linear_sum_assignment(np.hstack([cost, unserved]))
    return [
        (jobs[row], vehicles[column], float(raw[row, column]))
        for row, column in zip(rows, columns, strict=True)
        if column < len(vehicles)
    ]


def _urgency_weights(
    jobs: list[Job], now: datetime | None
) -> "np.ndarray[tuple[int], np.dtype[np.float64]]":
    levels = {priority: rank for rank, priority in enumerate(sorted({j.priority for j in jobs}))}
    weights = np.array([1.0 + levels[job.priority] for job in jobs])
    if now is not None:
        for row, job in enumerate(jobs):
            if job.deadline is not None and job.deadline - now <= DUE_SOON:
                weights[row] *= 2.0
    return weights


def _by_idle_time(candidates: Sequence[Candidate]) -> list[Candidate]:
    """Longest idle first: never-used vehicles, then by the end of their last order."""
    return sorted(candidates, key=lambda v: (_timestamp(v.idle_since, -math.inf), v.key))


def _timestamp(moment: datetime | None, default: float) -> float:
    return moment.timestamp() if moment is not None else default


def _waiting_note(
    job: Job, candidates: Sequence[Candidate], distances: dict[str, dict[str, float]]
) -> str:
    able = [v for v in candidates if v.node in distances[job.pickup]]
    if len(able) < len(candidates):
        return (
            f"waiting: the vehicles that can reach {job.station} are busy with more urgent orders"
        )
    return "waiting for a free vehicle: more urgent orders took the idle ones"
