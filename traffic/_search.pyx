# cython: language_level=3, boundscheck=False, wraparound=False, cdivision=True
# distutils: language = c++
"""The SIPP search loop compiled (Cython, C++ containers): `traffic.sipp_loop.run`, same answer.

States, moves and heuristic tables are read from flat arrays, the open list is a binary heap
of structs ordered like the Python tuples (f, -arrival, push count), and safe intervals are
computed from the reservation lists once per resource and search, as
`ReservationTable._between` does. `traffic.speedups` loads it when built and current.
"""

from libcpp.algorithm cimport pop_heap, push_heap
from libcpp.unordered_map cimport unordered_map
from libcpp.utility cimport pair
from libcpp.vector cimport vector

import operator

import numpy as np

from traffic._holds cimport Hold

ctypedef pair[long long, double] Link  # parent key, departure (-inf: a dwell)

cdef double INF = float("inf")
cdef int SHIFT = 24
cdef long long UNIT = 1LL << 24
_key = operator.attrgetter("key")  # a hold's sort key, as ReservationTable sorts by it
cdef long long YIELD_EVERY = 64  # expansions between two offers of the GIL (tens of µs)


cdef struct Entry:
    double f
    double neg_t
    long long pushes
    long long key
    double end
    long long s
    long long stage
    double c  # the move cost so far (0 without one)


cdef inline bint before(const Entry& a, const Entry& b) noexcept nogil:
    if a.f != b.f:
        return a.f < b.f
    if a.neg_t != b.neg_t:
        return a.neg_t < b.neg_t
    return a.pushes < b.pushes


cdef inline bint after(const Entry& a, const Entry& b) noexcept nogil:
    return before(b, a)  # std's heaps keep the largest first: this makes it the best


cdef inline void heap_push(vector[Entry]& heap, Entry item) noexcept nogil:
    heap.push_back(item)
    push_heap(heap.begin(), heap.end(), &after)


cdef inline Entry heap_pop(vector[Entry]& heap) noexcept nogil:
    pop_heap(heap.begin(), heap.end(), &after)
    cdef Entry top = heap.back()
    heap.pop_back()
    return top


cdef class Moves:
    """A class graph's states and moves as flat arrays (built once per graph)."""

    cdef long long[::1] node_of
    cdef long long[::1] ptr
    cdef long long[::1] to_node
    cdef long long[::1] seg
    cdef double[::1] tau
    cdef long long[::1] to_state
    cdef double[::1] turn

    def __init__(self, graph):
        count = graph.state_count
        flat = [m for moves in graph.moves for m in moves]
        self.node_of = np.asarray(graph.node_of, dtype=np.int64)
        self.ptr = np.cumsum([0] + [len(moves) for moves in graph.moves], dtype=np.int64)
        self.to_node = np.asarray([m[0] for m in flat], dtype=np.int64)
        self.seg = np.asarray([m[1] for m in flat], dtype=np.int64)
        self.tau = np.asarray([m[2] for m in flat], dtype=np.float64)
        self.to_state = np.asarray([m[3] for m in flat], dtype=np.int64)
        self.turn = np.asarray([m[4] for m in flat], dtype=np.float64)
        assert len(self.ptr) == count + 1


cdef class Gaps:
    """Safe intervals per resource for one search (flattened (from, to) pairs).

    Computed here from the reservation table's lists, exactly as
    `ReservationTable._between` does (its cache of shared gaps is a shortcut to the same
    answer, and most lists a search reads were re-timed since they were cached).
    """

    cdef unordered_map[long long, vector[double]] cache
    cdef object table
    cdef object blocked
    cdef object unsorted
    cdef long long vehicle
    cdef bint shared

    def __init__(self, table, long long vehicle, bint shared):
        self.table = table
        self.shared = shared
        self.blocked = table.blocked
        self.unsorted = table.unsorted
        self.vehicle = vehicle

    cdef vector[double]* of(self, long long resource):
        if self.cache.find(resource) != self.cache.end():
            return &self.cache[resource]
        cdef list holds = <list>self.blocked[resource]
        if resource in self.unsorted:
            if self.shared:  # other threads may use the table: a sorted copy
                holds = sorted(holds, key=_key)
            else:
                self.table.sort(resource)
                holds = <list>self.blocked[resource]
        cdef vector[double]* flat = &self.cache[resource]
        cdef double free_from = -INF
        cdef Hold hold
        for item in holds:
            hold = <Hold?>item
            if hold.vehicle == self.vehicle:
                continue
            if hold.key > free_from:
                flat.push_back(free_from)
                flat.push_back(hold.key)
            if hold.end > free_from:
                free_from = hold.end
        if free_from < INF:
            flat.push_back(free_from)
            flat.push_back(INF)
        return flat


def moves_of(graph):
    """The flat moves of `graph`, cached on it."""
    cached = getattr(graph, "_native_moves", None)
    if cached is None:
        cached = graph._native_moves = Moves(graph)
    return cached


def run(p):
    """Search `p` (a `traffic.sipp_loop.Problem`); the chain of the path found, or None."""
    cdef Moves m = moves_of(p.graph)
    cdef Gaps gaps = Gaps(p.table, p.vehicle, p.shared)
    graph = p.graph
    cost_to = graph.cost_to
    goals_py = p.goals
    cdef long long last = len(goals_py) - 1
    cdef vector[long long] goal_node
    cdef vector[double] goal_dwell
    for node, dwell in goals_py:
        goal_node.push_back(node)
        goal_dwell.push_back(dwell)
    cdef vector[double*] tables  # p.tables keeps the arrays alive
    cdef double[::1] view
    for table in p.tables:
        view = table
        tables.push_back(&view[0])
    # the start's moves when its heading is no graph state ("outside")
    cdef long long outside = graph.state_count
    outside_moves = graph._moves(p.start, p.heading)
    cdef long long span = outside + 1
    cdef long long start = p.start
    cdef long long start_key = (<long long>p.start_state) << SHIFT
    cdef double weight = p.weight
    cdef long long max_expansions = p.max_expansions
    cdef bint partial = p.partial
    cdef bint refuge = p.refuge
    avoid = p.avoid
    refuge_cost = p.refuge_cost
    cdef double t0 = p.t0
    cdef double h_start = p.h_start
    # With a move cost a state is better when its arrival plus cost is smaller; the cost is
    # kept beside (`spent`, read only when there is a cost: the default loop is unchanged).
    cdef bint has_cost = p.move_cost is not None
    cdef double leave = p.leave  # grid rules (>= 0): s a node stays held after the departure
    cdef double[::1] move_cost
    if has_cost:
        move_cost = np.ascontiguousarray(p.move_cost, dtype=np.float64)
    cdef unordered_map[long long, double] spent
    cdef double c, cc

    cdef unordered_map[long long, double] best
    cdef unordered_map[long long, Link] parents
    cdef unordered_map[long long, double].iterator found
    parents[start_key] = Link(-1, -INF)
    best[start_key] = t0
    cdef vector[Entry] heap
    heap_push(heap, Entry(t0 + weight * (h_start if h_start < INF else 0.0), -t0, 0, start_key,
                          p.deadline, p.start_state, 0, 0.0))
    cdef bint have_nearest = False
    cdef double near_score = 0.0, near_t = 0.0
    cdef long long near_key = 0
    cdef long long pushes = 0, expansions = 0
    cdef Entry e
    cdef double t, end, h, tau, turning, earliest, latest, ws, we, lo, hi, vs, ve, dep, arrive
    cdef double t2, cost, score, bound
    cdef long long key, s, stage, u, child, child_base, base, i, j, lo_m, hi_m, v, seg, vs_
    cdef long long idx, nn, ns
    lo_m = 0
    cdef vector[double]* node_gaps
    cdef vector[double]* seg_gaps
    cdef double* table_h
    cdef bint is_outside
    while heap.size():
        e = heap_pop(heap)
        t = -e.neg_t
        key, end, s, stage, c = e.key, e.end, e.s, e.stage, e.c
        found = best.find(key)
        if found != best.end():
            if has_cost:
                if best[key] + spent[key] < t + c:
                    continue
            elif (<double>best[key]) < t:
                continue
        expansions += 1
        if expansions > max_expansions:
            break
        if expansions % YIELD_EVERY == 0:
            with nogil:  # let a thread waiting for the GIL (paho's) run now and then
                pass
        is_outside = s == outside
        u = start if is_outside else m.node_of[s]
        if stage > last + 1:
            return _chain(parents, best, parents[key].first), True, True
        if stage > last:  # the refuge stage
            if end == INF and u not in avoid:
                cost = refuge_cost[u] if refuge_cost is not None else 0.0
                if cost <= 0.0:
                    return _chain(parents, best, key), True, True
                child = key + span * UNIT
                if best.find(child) == best.end():
                    best[child] = t
                    if has_cost:
                        spent[child] = c
                    parents[child] = Link(key, -INF)
                    pushes += 1
                    heap_push(heap, Entry(t + c + cost, -t, pushes, child, end, s, stage + 1, c))
        elif u == goal_node[stage]:
            if stage == last and not refuge:
                if end == INF:
                    return _chain(parents, best, key), True, False
            else:
                t2 = t + goal_dwell[stage]
                child = key + span * UNIT
                found = best.find(child)
                if t2 < end and (found == best.end() or (
                        t2 + c < best[child] + spent[child] if has_cost else t2 < best[child])):
                    best[child] = t2
                    if has_cost:
                        spent[child] = c
                    parents[child] = Link(key, -INF)
                    pushes += 1
                    if is_outside:
                        h = cost_to(p.tables[stage + 1], u, p.heading)
                    else:
                        h = tables[stage + 1][s]
                    heap_push(heap, Entry(t2 + c + weight * h, -t2, pushes, child, end, s,
                                          stage + 1, c))
        if partial and end == INF and stage == last:
            if is_outside:
                score = cost_to(p.tables[last], u, p.heading)
            else:
                score = tables[last][s]
            if not have_nearest or score < near_score or (score == near_score and t < near_t):
                have_nearest, near_score, near_t, near_key = True, score, t, key
        table_h = tables[stage]
        base = stage * span
        if is_outside:
            nn = len(outside_moves)
        else:
            lo_m, hi_m = m.ptr[s], m.ptr[s + 1]
            nn = hi_m - lo_m
        for i in range(nn):
            if is_outside:
                v, seg, tau, vs_, turning = outside_moves[i]
            else:
                j = lo_m + i
                v, seg, tau, vs_, turning = m.to_node[j], m.seg[j], m.tau[j], m.to_state[j], m.turn[j]
            h = table_h[vs_]
            if h == INF and not partial:
                continue
            earliest = t + turning
            latest = end - (tau if leave < 0 else leave)  # u is held until then
            if earliest > latest:
                continue
            node_gaps = gaps.of(v)
            seg_gaps = gaps.of(seg)
            child_base = (base + vs_) << SHIFT
            cc = c + move_cost[lo_m + i] if has_cost and not is_outside else c
            for j in range(0, <long long>seg_gaps.size(), 2):
                ws, we = seg_gaps[0][j], seg_gaps[0][j + 1]
                if ws > latest:
                    break
                lo = earliest if earliest > ws else ws
                bound = we - tau
                hi = latest if latest < bound else bound
                if lo > hi:
                    continue
                ns = <long long>node_gaps.size()
                for idx in range(0, ns // 2):
                    vs, ve = node_gaps[0][2 * idx], node_gaps[0][2 * idx + 1]
                    if vs > hi:
                        break
                    dep = lo if lo > vs else vs
                    arrive = dep + tau
                    if dep > hi or arrive >= ve:
                        continue
                    child = child_base + idx + 1
                    found = best.find(child)
                    if found == best.end() or (arrive + cc < best[child] + spent[child]
                                               if has_cost else arrive < best[child]):
                        best[child] = arrive
                        if has_cost:
                            spent[child] = cc
                        parents[child] = Link(key, dep)
                        pushes += 1
                        heap_push(heap, Entry(arrive + cc + weight * (h if h < INF else 0.0),
                                              -arrive, pushes, child, ve, vs_, stage, cc))
    if partial and have_nearest and near_key != start_key:
        return _chain(parents, best, near_key), False, False
    return None


cdef list _chain(unordered_map[long long, Link]& parents,
                 unordered_map[long long, double]& best, long long key):
    cdef list chain = []
    cdef long long current = key
    cdef Link parent
    while current >= 0:
        parent = parents[current]
        chain.append((current, best[current], parent.second))
        current = parent.first
    chain.reverse()
    return chain
