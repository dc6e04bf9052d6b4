"""Release timings are kept as a histogram (`Timings`): its percentiles are those of the sorted
samples to within a bucket (1 %), and a run saved with the timings as lists loads into it."""

import pickle

from hypothesis import given
from hypothesis import strategies as st

from traffic.des_records import SimStats, Timings

durations = st.lists(
    st.one_of(st.just(0.0), st.floats(min_value=1e-7, max_value=10.0)), min_size=1, max_size=300
)


def _sorted_pct(values: list[float], q: float) -> float:
    ordered = sorted(values)
    return ordered[min(len(ordered) - 1, int(len(ordered) * q / 100))]


@given(durations, st.sampled_from([0, 50, 95, 99, 100]))
def test_a_percentile_is_the_sorted_samples_one_at_most_a_bucket_high(
    values: list[float], q: float
) -> None:
    timings = Timings(values)
    exact = _sorted_pct(values, q)
    assert exact <= timings.percentile(q) * (1 + 1e-9)
    assert timings.percentile(q) <= exact * Timings.GROWTH * (1 + 1e-9)
    assert timings.max == max(values)
    assert len(timings) == len(values)


@given(durations, st.floats(min_value=1e-6, max_value=1.0))
def test_the_count_over_a_limit_misses_only_samples_within_a_bucket_of_it(
    values: list[float], limit: float
) -> None:
    counted = Timings(values).count_over(limit)
    assert sum(v > limit * Timings.GROWTH**2 for v in values) <= counted
    assert counted <= sum(v > limit for v in values)


def test_count_sum_and_maximum_are_exact() -> None:
    timings = Timings([0.001, 0.002, 0.0])
    assert (timings.count, timings.zeros, timings.max) == (3, 1, 0.002)
    assert abs(timings.total - 0.003) < 1e-12
    assert timings.percentile(0) == 0.0  # the zero sorts first
    assert Timings().percentile(99) == 0.0


def test_memory_does_not_grow_with_repeated_samples() -> None:
    timings = Timings([0.0001] * 10_000 + [0.0002] * 10_000)
    assert len(timings.buckets) == 2
    assert timings.percentile(40) < 0.000102 < timings.percentile(60)


def test_stats_saved_with_timing_lists_load_as_histograms() -> None:
    old = SimStats()
    old.__dict__["release_seconds"] = [0.0001, 0.0003]  # as a run of the nineteenth round
    old.__dict__["release_cpu_seconds"] = [0.0002]
    loaded = pickle.loads(pickle.dumps(old))
    assert loaded.release_seconds == Timings([0.0001, 0.0003])
    assert loaded.release_cpu_seconds.count == 1
    loaded.release_seconds.append(0.0005)
    assert loaded.release_seconds.max == 0.0005
