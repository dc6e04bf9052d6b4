# cython: language_level=3, boundscheck=False, wraparound=False, cdivision=True
# distutils: language = c++
"""Holds and re-timing compiled (Cython): twins of `traffic.reservations.PyHold` and
`traffic.timing.propagate_plain`, same results (`tests/traffic/test_speedups.py`).

`Hold` is a C struct (its fields are read millions of times by re-timing and the search);
`traffic.speedups` loads this module when it is built (`make venv`) and current.
"""

import heapq


cdef class Hold:
    """One vehicle's claim on one resource during one step of its plan (see
    `traffic.reservations.PyHold`, its plain-Python twin; fields in `_holds.pxd`)."""

    def __init__(self, long long vehicle, long long resource, long long index, double start,
                 double end, conflicts):
        self.vehicle, self.resource, self.index = vehicle, resource, index
        self.start, self.end, self.key = start, end, start
        self.released = False
        self.conflicts = conflicts

    def __repr__(self):
        state = "released" if self.released else "planned"
        return (
            f"Hold(v{self.vehicle} r{self.resource} #{self.index} "
            f"{self.start:.2f}-{self.end:.2f} {state})"
        )


def propagate(vehicles, table, graphs, pushes):
    """Apply pushes (time, vehicle, index: no departure from that index before time); the
    number of steps moved. `traffic.timing.propagate`, step for step."""
    heap = list(pushes)
    heapq.heapify(heap)
    pop = heapq.heappop
    unsorted, stale = table.unsorted, table._stale
    cdef long long moved = 0, idx, i, last
    cdef double t, arrive, ready
    cdef Hold edge, node, hold
    cdef list depart, arrivals, edge_holds, node_holds, route
    while heap:
        t, idx, i = pop(heap)
        v = vehicles[idx]
        route, depart = v.route, v.depart
        last = len(route) - 1
        if i >= last or t <= <double>depart[i]:
            continue
        graph = graphs[v.cls]
        travel = graph.travel
        arrivals, edge_holds, node_holds = v.arrive, v.edge_holds, v.node_holds
        while True:
            depart[i] = t
            arrive = t + <double>travel[(route[i], route[i + 1])]
            edge, node = <Hold?>edge_holds[i + 1], <Hold?>node_holds[i + 1]
            for hold in (edge, node):
                if hold.start < t:
                    hold.start = t
                    if not hold.released:  # ReservationTable.retimed
                        hold.key = hold.start
                        unsorted.update(hold.conflicts)
            arrivals[i + 1] = arrive
            for hold in (edge, <Hold?>node_holds[i]):
                if hold.end < arrive:
                    hold.end = arrive
                    stale.update(hold.conflicts)  # ReservationTable.ended
                    _push_followers(table, hold, idx, heap)
            moved += 1
            i += 1
            if i >= last:
                break
            ready = arrive + _stay(v, graph, i)
            if ready <= <double>depart[i]:
                break  # a planned wait absorbs the delay
            t = ready
    return moved


cdef double _stay(v, graph, long long i):
    """Seconds the vehicle spends at route index i before leaving (`traffic.timing.stay`)."""
    cdef double seconds = graph.turn(v.headings[i], v.headings[i + 1])
    cdef long long passed = v.passed
    for (_, dwell), stop in zip(v.goals, v.stops):
        if stop == i and i > passed:
            seconds += dwell
    return seconds


cdef void _push_followers(table, Hold hold, long long idx, list heap) except *:
    """Push the other vehicles' holds queued behind `hold` that now start before it ends."""
    cdef list queue = table.blocked[hold.resource]
    cdef Py_ssize_t position = -1, k, n = len(queue)
    for k in range(n):
        if queue[k] is hold:
            position = k
            break
    if position < 0:
        return  # already cleared
    cdef double end = hold.end
    cdef bint ordered = hold.resource not in table.unsorted  # keys ascend: stop at the first >= end
    cdef Hold follower
    for k in range(position + 1, n):
        follower = <Hold?>queue[k]
        if follower.key >= end and ordered:
            break
        if follower.vehicle != idx and not follower.released and follower.start < end:
            heapq.heappush(heap, (end, follower.vehicle, follower.index - 1))
