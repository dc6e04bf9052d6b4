# The compiled hold (traffic/_holds.pyx), shared with the compiled search (traffic/_search.pyx).

cdef class Hold:
    cdef public long long vehicle
    cdef public long long resource
    cdef public long long index  # route index of the step
    cdef public double start  # planned entry (s)
    cdef public double end  # planned clearing (s); inf for a vehicle parked until further notice
    cdef public double key  # sort key: start, or -inf once released
    cdef public bint released
    cdef public object conflicts  # the lists this hold is in
