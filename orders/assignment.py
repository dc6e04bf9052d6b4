"""Which idle vehicle takes which pending order: a batch assignment, framework-free.

Dispatch (`orders.services.dispatch`) turns rows into `Job`s and `Candidate`s, and the benchmark
builds them in memory. `plan_batch` solves one assignment problem per cycle with
`scipy.optimize.linear_sum_assignment` over the cost (travel time, or distance) from each
vehicle to each order's first stop; `plan_greedy` is the nearest-vehicle loop it replaced, kept
as the baseline. A vehicle's `profile` (its vehicle type) selects its cost table, so vehicles of
different types see different routes; a job's `allowed` names the only vehicles that may take it
(intended vehicle, vehicle type, capabilities).

Rules of the batch:
- Only as many orders as there are idle vehicles enter a cycle, most urgent first (priority,
  then deadline, then age). An order no idle vehicle can reach does not take a place.
- Distances are weighted by urgency, so in a contest for a near vehicle the more urgent order
  wins: weight 1 + the order's rank among the distinct priorities of the batch, doubled when
  its deadline is near or past.
- Ties between vehicles at the same distance go to the one idle the longest (fairness).
"""

import math
from collections import Counter, defaultdict
from collections.abc import Callable, Hashable, Sequence
from dataclasses import dataclass, field
from datetime import datetime, timedelta

import numpy as np
from scipy.optimize import linear_sum_assignment

DUE_SOON = timedelta(minutes=15)  # a deadline this close makes an order count double
_TIE_BREAK = 1e-3  # metres per rank of idle time: decides between vehicles within ~0.2 m

DistancesTo = Callable[[str], dict[str, float]]
# Costs to a goal for vehicles of one profile (vehicle type): (goal, profile) -> {node: cost}.
ProfileCostsTo = Callable[[str, Hashable], dict[str, float]]


@dataclass(frozen=True)
class Job:
    """A pending order as dispatch sees it."""

    key: int
    pickup: str  # node id of the source station
    station: str  # station id, for the notes
    priority: int = 0
    deadline: datetime | None = None
    created: datetime | None = None
    allowed: frozenset[int] | None = None  # keys of the only candidates that may take it


@dataclass(frozen=True)
class Candidate:
    """An idle vehicle: where it stands, since when it has had nothing to do, and the profile
    (vehicle type) whose cost table prices its travel (None: the default table)."""

    key: int
    node: str
    idle_since: datetime | None = None  # None: never had an order, the longest idle of all
    profile: Hashable | None = None


class _Costs:
    """Cost from a candidate to a job's pickup, cached per (pickup, profile); None: cannot.

    Profiles are numbered once per cycle: hashing a profile (a dataclass) for every lookup
    cost more than the lookups themselves."""

    def __init__(
        self,
        distances_to: DistancesTo,
        by_profile: ProfileCostsTo | None,
        candidates: Sequence[Candidate],
    ) -> None:
        self._default, self._by_profile = distances_to, by_profile
        self._tables: dict[tuple[str, int], dict[str, float]] = {}
        self._candidates = candidates
        numbers: dict[Hashable | None, int] = {}
        self._profile: dict[int, int] = {}  # candidate key -> profile number
        # Vehicles per profile and node, so "how many can reach this pickup" costs one lookup
        # per distinct (profile, node), not one per vehicle.
        self._nodes: dict[int, Counter[str]] = defaultdict(Counter)
        for vehicle in candidates:
            number = numbers.setdefault(vehicle.profile, len(numbers))
            self._profile[vehicle.key] = number
            self._nodes[number][vehicle.node] += 1
        self._profiles = list(numbers)
        self._able: dict[tuple[str, frozenset[int] | None], int] = {}

    def __call__(self, job: Job, vehicle: Candidate) -> float | None:
        if job.allowed is not None and vehicle.key not in job.allowed:
            return None
        return self.table(job.pickup, self._profile[vehicle.key]).get(vehicle.node)

    def table(self, pickup: str, number: int) -> dict[str, float]:
        key = (pickup, number)
        table = self._tables.get(key)
        if table is None:
            profile = self._profiles[number]
            if profile is None or self._by_profile is None:
                table = self._default(pickup)
            else:
                table = self._by_profile(pickup, profile)
            self._tables[key] = table
        return table

    def able(self, job: Job) -> int:
        """How many of all candidates can take `job` (this runs for every job of a backlog)."""
        key = (job.pickup, job.allowed)
        total = self._able.get(key)
        if total is not None:  # many jobs share a pickup station (and a restriction)
            return total
        if job.allowed is not None:
            total = sum(1 for v in self._candidates if self(job, v) is not None)
        else:
            total = 0
            for number, nodes in self._nodes.items():
                table = self.table(job.pickup, number)
                total += sum(count for node, count in nodes.items() if node in table)
        self._able[key] = total
        return total

    def row(self, job: Job, vehicles: Sequence[Candidate]) -> list[float | None]:
        """Costs from each of `vehicles` to `job` (one table lookup per profile)."""
        numbers = [self._profile[v.key] for v in vehicles]
        tables = {n: self.table(job.pickup, n) for n in set(numbers)}
        allowed = job.allowed
        return [
            None if allowed is not None and v.key not in allowed else tables[n].get(v.node)
            for v, n in zip(vehicles, numbers, strict=True)
        ]


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
    by_profile: ProfileCostsTo | None = None,
) -> Plan:
    """Assign up to len(candidates) of the most urgent reachable jobs at least weighted cost."""
    costs = _Costs(distances_to, by_profile, candidates)
    plan, reachable = _triage(jobs, candidates, costs)
    free = _by_idle_time(candidates)
    waiting, unserved = reachable, []
    while waiting and free:
        # A job the solver leaves out cannot reach any vehicle still free (serving it would
        # always be cheaper), so it waits for the next cycle; the next jobs get a chance.
        batch, waiting = waiting[: len(free)], waiting[len(free) :]
        assigned = _solve(batch, free, costs, now)
        plan.pairs.extend(assigned)
        served = {job.key for job, _, _ in assigned}
        taken = {vehicle.key for _, vehicle, _ in assigned}
        unserved += [job for job in batch if job.key not in served]
        free = [vehicle for vehicle in free if vehicle.key not in taken]
    for job in unserved + waiting:
        plan.notes[job.key] = _waiting_note(job, candidates, costs)
    return plan


def plan_greedy(
    jobs: Sequence[Job],
    candidates: Sequence[Candidate],
    distances_to: DistancesTo,
    *,
    by_profile: ProfileCostsTo | None = None,
) -> Plan:
    """The baseline: in urgency order, each job takes the nearest free vehicle."""
    costs = _Costs(distances_to, by_profile, candidates)
    plan, reachable = _triage(jobs, candidates, costs)
    free = list(candidates)
    for job in reachable:
        options = [(cost, v.key, v) for v in free if (cost := costs(job, v)) is not None]
        if not options:
            plan.notes[job.key] = _waiting_note(job, candidates, costs)
            continue
        cost, _, vehicle = min(options, key=lambda option: option[:2])
        plan.pairs.append((job, vehicle, cost))
        free.remove(vehicle)
    return plan


def _triage(
    jobs: Sequence[Job], candidates: Sequence[Candidate], costs: _Costs
) -> tuple[Plan, list[Job]]:
    """Sort by urgency and note the jobs no idle vehicle can reach."""
    plan = Plan()
    reachable: list[Job] = []
    for job in sorted(jobs, key=urgency_key):
        if costs.able(job):
            reachable.append(job)
        elif not candidates:
            plan.notes[job.key] = "no vehicle available"
        elif job.allowed is not None and not job.allowed & {v.key for v in candidates}:
            plan.notes[job.key] = "waiting: no vehicle allowed to take it is idle"
        else:
            plan.notes[job.key] = f"no vehicle can reach {job.station}"
    return plan, reachable


def _solve(
    jobs: list[Job],
    vehicles: list[Candidate],
    costs: _Costs,
    now: datetime | None,
) -> list[tuple[Job, Candidate, float]]:
    """One assignment problem. Besides the vehicles, each job (sorted by urgency) may take a
    column of its own meaning "not served this time", at a price that grows with its urgency in
    steps larger than any sum of travel costs: so the most urgent jobs are served first, and
    only among equally served sets does travel decide."""
    raw = np.full((len(jobs), len(vehicles)), np.inf)
    for row, job in enumerate(jobs):
        for column, cost in enumerate(costs.row(job, vehicles)):
            if cost is not None:
                raw[row, column] = cost
    weighted = raw * _urgency_weights(jobs, now)[:, None]
    weighted += np.arange(len(vehicles))[None, :] * _TIE_BREAK  # vehicles sorted by idle time
    finite = weighted[np.isfinite(weighted)]
    if not finite.size:
        return []
    step = float(finite.max()) * len(jobs) + 1.0
    unserved = np.full((len(jobs), len(jobs)), np.inf)
    np.fill_diagonal(unserved, step * (len(jobs) - np.arange(len(jobs))))
    rows, columns = linear_sum_assignment(np.hstack([weighted, unserved]))
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


def _waiting_note(job: Job, candidates: Sequence[Candidate], costs: _Costs) -> str:
    if costs.able(job) < len(candidates):
        return (
            f"waiting: the vehicles that can reach {job.station} are busy with more urgent orders"
        )
    return "waiting for a free vehicle: more urgent orders took the idle ones"
