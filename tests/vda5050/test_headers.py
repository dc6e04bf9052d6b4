"""headerId counters and protocol timestamps."""

from __future__ import annotations

import re
import threading
from datetime import UTC, datetime, timedelta, timezone

import pytest

from vda5050 import (
    HeaderCounter,
    TimestampError,
    TopicError,
    TopicKind,
    VersionError,
    format_timestamp,
    now_timestamp,
    parse_timestamp,
)

TS_2X = re.compile(r"\d{4}-\d{2}-\d{2}T\d{2}:\d{2}:\d{2}\.\d{2}Z")
TS_3X = re.compile(r"\d{4}-\d{2}-\d{2}T\d{2}:\d{2}:\d{2}\.\d{3}Z")


# --- HeaderCounter ----------------------------------------------------------------------


def test_counter_starts_at_zero_and_increments() -> None:
    counter = HeaderCounter()
    assert [counter.next_id("Acme", "AGV-1", TopicKind.ORDER) for _ in range(4)] == [0, 1, 2, 3]


def test_counter_is_per_vehicle_and_topic() -> None:
    counter = HeaderCounter()
    counter.next_id("Acme", "AGV-1", TopicKind.ORDER)
    counter.next_id("Acme", "AGV-1", TopicKind.ORDER)
    assert counter.next_id("Acme", "AGV-1", TopicKind.INSTANT_ACTIONS) == 0
    assert counter.next_id("Acme", "AGV-2", TopicKind.ORDER) == 0
    assert counter.next_id("Other", "AGV-1", TopicKind.ORDER) == 0
    assert counter.next_id("Acme", "AGV-1", TopicKind.ORDER) == 2


def test_counter_accepts_kind_as_string() -> None:
    counter = HeaderCounter()
    counter.next_id("Acme", "AGV-1", TopicKind.STATE)
    assert counter.next_id("Acme", "AGV-1", "state") == 1
    with pytest.raises(TopicError):
        counter.next_id("Acme", "AGV-1", "stat")


def test_counter_wraps_at_2_pow_32() -> None:
    counter = HeaderCounter()
    counter.set_next("Acme", "AGV-1", TopicKind.ORDER, 2**32 - 2)
    ids = [counter.next_id("Acme", "AGV-1", TopicKind.ORDER) for _ in range(4)]
    assert ids == [2**32 - 2, 2**32 - 1, 0, 1]


def test_peek_does_not_advance() -> None:
    counter = HeaderCounter()
    assert counter.peek("Acme", "AGV-1", TopicKind.ORDER) == 0
    counter.next_id("Acme", "AGV-1", TopicKind.ORDER)
    assert counter.peek("Acme", "AGV-1", TopicKind.ORDER) == 1
    assert counter.peek("Acme", "AGV-1", TopicKind.ORDER) == 1


@pytest.mark.parametrize("value", [-1, 2**32, 2**40])
def test_set_next_rejects_out_of_range(value: int) -> None:
    with pytest.raises(ValueError, match="headerId"):
        HeaderCounter().set_next("Acme", "AGV-1", TopicKind.ORDER, value)


def test_set_next_rejects_non_int() -> None:
    with pytest.raises(TypeError):
        HeaderCounter().set_next("Acme", "AGV-1", TopicKind.ORDER, True)


def test_reset_one_topic_or_whole_vehicle() -> None:
    counter = HeaderCounter()
    for kind in (TopicKind.ORDER, TopicKind.INSTANT_ACTIONS):
        for serial in ("AGV-1", "AGV-2"):
            counter.set_next("Acme", serial, kind, 10)
    counter.reset("Acme", "AGV-1", TopicKind.ORDER)
    assert counter.peek("Acme", "AGV-1", TopicKind.ORDER) == 0
    assert counter.peek("Acme", "AGV-1", TopicKind.INSTANT_ACTIONS) == 10
    counter.reset("Acme", "AGV-1")
    assert counter.peek("Acme", "AGV-1", TopicKind.INSTANT_ACTIONS) == 0
    assert counter.peek("Acme", "AGV-2", TopicKind.ORDER) == 10


def test_counter_is_thread_safe() -> None:
    counter = HeaderCounter()
    results: list[int] = []
    lock = threading.Lock()

    def worker() -> None:
        local = [counter.next_id("Acme", "AGV-1", TopicKind.ORDER) for _ in range(2000)]
        with lock:
            results.extend(local)

    threads = [threading.Thread(target=worker) for _ in range(8)]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    assert sorted(results) == list(range(16000))


# --- timestamps -------------------------------------------------------------------------

DT = datetime(2024, 3, 11, 11, 40, 3, 129999, tzinfo=UTC)


@pytest.mark.parametrize("version", ["2.0.0", "2.1.0"])
def test_format_2x_has_two_fraction_digits(version: str) -> None:
    assert format_timestamp(DT, version) == "2024-03-11T11:40:03.12Z"


def test_format_3x_has_three_fraction_digits() -> None:
    assert format_timestamp(DT, "3.0.0") == "2024-03-11T11:40:03.129Z"


def test_format_truncates_instead_of_rounding_into_next_day() -> None:
    late = datetime(2024, 12, 31, 23, 59, 59, 999999, tzinfo=UTC)
    assert format_timestamp(late, "2.0.0") == "2024-12-31T23:59:59.99Z"
    assert format_timestamp(late, "3.0.0") == "2024-12-31T23:59:59.999Z"


def test_format_zero_fraction_and_small_year() -> None:
    assert format_timestamp(datetime(2024, 1, 2, 3, 4, 5, tzinfo=UTC), "2.0.0") == (
        "2024-01-02T03:04:05.00Z"
    )
    assert format_timestamp(datetime(999, 1, 1, tzinfo=UTC), "2.0.0") == ("0999-01-01T00:00:00.00Z")


def test_format_converts_to_utc() -> None:
    cest = timezone(timedelta(hours=2))
    local = datetime(2024, 3, 11, 1, 0, 0, 500000, tzinfo=cest)
    assert format_timestamp(local, "2.1.0") == "2024-03-10T23:00:00.50Z"


def test_format_rejects_naive_datetime() -> None:
    with pytest.raises(TimestampError):
        format_timestamp(datetime(2024, 3, 11, 11, 40, 3), "2.0.0")  # noqa: DTZ001


def test_format_rejects_bad_version() -> None:
    with pytest.raises(VersionError):
        format_timestamp(DT, "latest")


def test_now_timestamp_per_version() -> None:
    before = datetime.now(UTC) - timedelta(seconds=1)
    text = now_timestamp("2.0.0")
    assert TS_2X.fullmatch(text)
    assert TS_3X.fullmatch(now_timestamp("3.0.0"))
    assert before <= parse_timestamp(text) <= datetime.now(UTC)


@pytest.mark.parametrize(
    ("text", "expected"),
    [
        ("2024-03-11T11:40:03.12Z", datetime(2024, 3, 11, 11, 40, 3, 120000, tzinfo=UTC)),
        ("2024-03-11T11:40:03.123Z", datetime(2024, 3, 11, 11, 40, 3, 123000, tzinfo=UTC)),
        ("2024-03-11T11:40:03Z", datetime(2024, 3, 11, 11, 40, 3, tzinfo=UTC)),
        ("2024-03-11T11:40:03.1Z", datetime(2024, 3, 11, 11, 40, 3, 100000, tzinfo=UTC)),
        ("2024-03-11T11:40:03.123456789Z", datetime(2024, 3, 11, 11, 40, 3, 123456, tzinfo=UTC)),
        ("2024-03-11T13:40:03.5+02:00", datetime(2024, 3, 11, 11, 40, 3, 500000, tzinfo=UTC)),
        ("2024-03-11T06:40:03-05:00", datetime(2024, 3, 11, 11, 40, 3, tzinfo=UTC)),
        ("2024-03-11T11:40:03+00:00", datetime(2024, 3, 11, 11, 40, 3, tzinfo=UTC)),
        ("2024-03-11t11:40:03.12z", datetime(2024, 3, 11, 11, 40, 3, 120000, tzinfo=UTC)),
        ("2024-03-11 11:40:03Z", datetime(2024, 3, 11, 11, 40, 3, tzinfo=UTC)),
        ("2024-03-11T11:40:03", datetime(2024, 3, 11, 11, 40, 3, tzinfo=UTC)),
        ("20240311T114003Z", datetime(2024, 3, 11, 11, 40, 3, tzinfo=UTC)),
        (" 2024-03-11T11:40:03Z\n", datetime(2024, 3, 11, 11, 40, 3, tzinfo=UTC)),
    ],
)
def test_parse_timestamp(text: str, expected: datetime) -> None:
    parsed = parse_timestamp(text)
    assert parsed == expected
    assert parsed.utcoffset() == timedelta(0)


@pytest.mark.parametrize(
    "text", ["", "yesterday", "2024-13-01T00:00:00Z", "2024-03-11T25:00:00Z", "11:40:03"]
)
def test_parse_timestamp_rejects(text: str) -> None:
    with pytest.raises(TimestampError):
        parse_timestamp(text)


def test_parse_timestamp_rejects_non_string() -> None:
    with pytest.raises(TimestampError):
        parse_timestamp(1710157203)  # type: ignore[arg-type]


@pytest.mark.parametrize("version", ["2.0.0", "3.0.0"])
def test_format_then_parse_round_trip(version: str) -> None:
    parsed = parse_timestamp(format_timestamp(DT, version))
    assert DT - timedelta(milliseconds=10) < parsed <= DT
