# cython: language_level=3, boundscheck=False, wraparound=False, cdivision=True
# distutils: language = c++
"""Holds and re-timing compiled (Cython): twins of `traffic.reservations.PyHold` and
`traffic.timing.propagate_plain`, same results (`tests/traffic/test_speedups.py`).

`Hold` is a C struct (its fields are read millions of times by re-timing and the search);
`traffic.speedups` loads this module when it is built (`make venv`) and current.
"""

cimport cython
from cpython.object cimport PyObject
from libcpp.algorithm cimport pop_heap, push_heap
from libc.stdint cimport uint64_t
from libcpp.vector cimport vector


# Not tracked by the garbage collector: a hold refers to nothing but its conflict tuple of
# ints, so no reference cycle runs through one, and control keeps a hundred thousand alive;
# tracked, each young collection walked the holds planned since the last one.
@cython.no_gc
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


cdef struct Step:
    # a push in the order of `traffic.timing.propagate_plain`'s tuples (key, -t, vehicle, index)
    double key  # the step's planned departure before the call
    double minus  # -t: the largest push of a step first
    long long vehicle
    long long index


cdef inline bint _before(Step a, Step b) noexcept:
    if a.key != b.key:
        return a.key < b.key
    if a.minus != b.minus:
        return a.minus < b.minus
    if a.vehicle != b.vehicle:
        return a.vehicle < b.vehicle
    return a.index < b.index


cdef inline bint _after(const Step& a, const Step& b) noexcept:
    return _before(b, a)  # std's heaps keep the largest first: this makes it the earliest


cdef inline void _heap_push(vector[Step]& heap, Step item) noexcept:
    heap.push_back(item)
    push_heap(heap.begin(), heap.end(), &_after)


cdef inline Step _heap_pop(vector[Step]& heap) noexcept:
    pop_heap(heap.begin(), heap.end(), &_after)
    cdef Step top = heap.back()
    heap.pop_back()
    return top


cdef struct Marked:
    # the conflict tuples done in this call of `propagate`, by address: an open-addressing set
    # (linear probing, a power-of-two table at most half full); std::unordered_set's prime
    # modulo and node per insert were two thirds of `_mark`
    vector[PyObject*] slots
    size_t count
    int bits


cdef inline bint _first_time(Marked& done, PyObject* item) noexcept:
    """Whether `item` is new to `done` (it is then added)."""
    cdef size_t mask, slot, k
    cdef vector[PyObject*] old
    if 2 * (done.count + 1) > done.slots.size():  # grow (first use: 64 slots)
        old.swap(done.slots)
        done.bits = 6 if done.bits == 0 else done.bits + 1
        done.slots.assign(<size_t>1 << done.bits, NULL)
        done.count = 0
        for k in range(old.size()):
            if old[k] != NULL:
                _first_time(done, old[k])
    mask = done.slots.size() - 1
    # Fibonacci hashing of the address (objects are 16-byte aligned: the low bits say little)
    slot = <size_t>(((<uint64_t><size_t>item >> 4) * <uint64_t>11400714819323198485ULL)
                    >> (64 - done.bits))
    while done.slots[slot] != NULL:
        if done.slots[slot] == item:
            return False
        slot = (slot + 1) & mask
    done.slots[slot] = item
    done.count += 1
    return True


cdef inline void _mark(set marks, Marked& done, tuple conflicts) except *:
    """Add the resources of `conflicts` to `marks`, once per call of `propagate`: the sets
    only grow during a call, and a conflict tuple is shared by every hold of one vehicle class
    on one resource (`traffic.footprint.ConflictSets`), so its address says it is done."""
    if not _first_time(done, <PyObject*>conflicts):
        return
    for r in conflicts:
        marks.add(r)


cdef inline void _start(Hold hold, double t, set unsorted, Marked& marked) except *:
    """Move a hold's start to `t` if later (`ReservationTable.retimed`)."""
    if hold.start < t:
        hold.start = t
        if not hold.released:
            hold.key = hold.start
            _mark(unsorted, marked, hold.conflicts)


cdef inline void _end(
    Hold hold, double end, set stale, Marked& marked, list fleet, list blocked, set unsorted,
    long long idx, vector[Step]& heap
) except *:
    """Move a hold's end to `end` if later (`ReservationTable.ended`) and push the holds
    queued behind it."""
    if hold.end < end:
        hold.end = end
        _mark(stale, marked, hold.conflicts)
        _push_followers(fleet, blocked, unsorted, hold, idx, heap)


def propagate(vehicles, table, graphs, pushes, double leave=-1.0):
    """Apply pushes (time, vehicle, index: no departure from that index before time); the
    number of steps moved. `traffic.timing.propagate`, step for step: steps in the order of
    their departure before the call, the largest push of a step first (a heap of C structs
    instead of tuples)."""
    cdef vector[Step] heap
    cdef Step item, entry
    cdef Marked marked_unsorted, marked_stale
    marked_unsorted.count = marked_stale.count = 0
    marked_unsorted.bits = marked_stale.bits = 0
    cdef list fleet = vehicles
    cdef set unsorted = table.unsorted, stale = table._stale
    cdef list blocked = table.blocked
    cdef long long moved = 0, idx, i, last
    cdef double t, arrive, ready, seconds, left
    for t, idx, i in pushes:
        item.key, item.minus = fleet[idx].depart[i], -t
        item.vehicle, item.index = idx, i
        _heap_push(heap, item)
    cdef Hold edge, node, here
    cdef list depart, arrivals, edge_holds, node_holds, route, headings, goals, stops
    cdef dict travel
    cdef long long passed, k, h0, h1
    while heap.size():
        item = _heap_pop(heap)
        t, idx, i = -item.minus, item.vehicle, item.index
        v = fleet[idx]
        route, depart = v.route, v.depart
        last = len(route) - 1
        if i >= last or t <= <double>depart[i]:
            continue
        graph = graphs[v.cls]
        travel = graph.travel
        arrivals, edge_holds, node_holds = v.arrive, v.edge_holds, v.node_holds
        headings, goals, stops, passed = v.headings, v.goals, v.stops, v.passed
        while True:
            depart[i] = t
            arrive = t + <double>travel[(route[i], route[i + 1])]
            edge, node = <Hold>edge_holds[i + 1], <Hold>node_holds[i + 1]  # never None here
            _start(edge, t, unsorted, marked_unsorted)
            _start(node, t, unsorted, marked_unsorted)
            arrivals[i + 1] = arrive
            # a node hold ends on arrival at the next node, or (grid rules) `leave` s after
            # the departure (`traffic.plans.node_hold_end`)
            left = arrive if leave < 0 else t + leave
            _end(edge, arrive, stale, marked_stale, fleet, blocked, unsorted, idx, heap)
            here = <Hold>node_holds[i]  # the node it leaves
            _end(here, left, stale, marked_stale, fleet, blocked, unsorted, idx, heap)
            moved += 1
            i += 1
            if i >= last:
                break
            seconds = 0.0  # the stay at i (`traffic.timing.stay`): turn, then dwells
            h0, h1 = headings[i], headings[i + 1]
            if h0 >= 0 and h0 != h1:  # else `graph.turn` is 0
                seconds = graph.turn(h0, h1)
            if i > passed:
                for k in range(len(stops)):
                    if <long long>stops[k] == i:
                        seconds += <double>goals[k][1]
            ready = arrive + seconds
            if ready <= <double>depart[i]:
                break  # a planned wait absorbs the delay
            entry.key, entry.minus, entry.vehicle, entry.index = depart[i], -ready, idx, i
            if heap.size() and _before(heap[0], entry):  # another step comes first
                _heap_push(heap, entry)
                break
            t = ready  # the next step is the next in order: no need to queue it
    return moved


cdef void _push_followers(
    list fleet, list blocked, set unsorted, Hold hold, long long idx, vector[Step]& heap
) except *:
    """Push the other vehicles' holds queued behind `hold` that now start before it ends."""
    cdef list queue = blocked[hold.resource]
    cdef Py_ssize_t position = -1, k, n = len(queue)
    for k in range(n):
        if queue[k] is hold:
            position = k
            break
    if position < 0:
        return  # already cleared
    cdef double end = hold.end
    cdef int ordered = -1  # keys ascend (not marked unsorted): stop at the first >= end
    cdef Hold follower
    cdef Step item
    for k in range(position + 1, n):
        follower = <Hold>queue[k]  # the lists hold only holds
        if follower.key >= end:
            if ordered < 0:  # asked once, and only here: a set lookup per call was 7 %
                ordered = hold.resource not in unsorted
            if ordered:
                break
        if follower.vehicle != idx and not follower.released and follower.start < end:
            item.index = follower.index - 1
            item.vehicle = follower.vehicle
            item.key = fleet[item.vehicle].depart[item.index]
            item.minus = -end
            _heap_push(heap, item)
