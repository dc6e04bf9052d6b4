"""The release-tail benchmark (`bench.traffic.release_tail`): repeats of a saved run make the
same calls, and each call's figure is its least CPU time over the repeats."""

from array import array
from pathlib import Path

from bench.traffic import long_run, release_tail
from tests.bench.test_traffic_checkpoints import _saved_at_first_cut


def test_repeats_of_a_saved_run_make_the_same_state_messages(tmp_path: Path) -> None:
    state = _saved_at_first_cut(tmp_path)
    first, second = (release_tail.drive(state, 30.0) for _ in range(2))
    assert first.calls == second.calls
    assert len(first.calls) == len(first.cpu) > 10
    after = long_run.load(state).after
    assert all(after < now <= after + 30.0 for _, _, now in first.calls)


def test_an_s2_instance_is_driven_from_its_start_the_same_each_time() -> None:
    source = release_tail.S2Start("MR23-I-04", delays=True)
    first, second = (release_tail.drive(source, 20.0) for _ in range(2))
    assert first.calls == second.calls
    assert len(first.calls) > 100
    assert all(0.0 < now <= 20.0 for _, _, now in first.calls)


def test_the_tail_counts_what_took_longer_than_a_millisecond() -> None:
    cpu = array("d", [1e-5] * 9_998 + [2e-3, 5e-4])
    figures = release_tail.tail(cpu)
    assert figures["over_1ms"] == 1
    assert figures["max_us"] == 2000.0
    assert figures["p50_us"] == 10.0
    assert figures["p99_99_us"] == 2000.0  # rank 9,999 of 10,000


def test_each_call_counts_with_its_least_time_over_the_repeats(tmp_path: Path) -> None:
    figures = release_tail.measure(_saved_at_first_cut(tmp_path), 20.0, 2)
    least, worst = figures["per_call_minimum"], figures["single_repeat_worst"]
    assert figures["state_messages"] > 10
    assert least["max_us"] <= worst["max_us"]
    assert least["over_1ms"] <= min(figures["single_repeats_over_1ms"])
    slowest = figures["slowest_calls"]
    assert len(slowest) == 5
    assert all(len(call["cpu_us"]) == 2 for call in slowest)
    assert min(slowest[0]["cpu_us"]) == least["max_us"]
