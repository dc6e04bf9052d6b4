"""The protocol session: header ids per topic, liveness from states, reconnects."""

from control.session import TIMEOUT_GRACE, Link, ProtocolSession, Verdict


def test_header_ids_duplicates_and_older_messages_are_dropped_and_gaps_counted() -> None:
    session = ProtocolSession()

    verdicts = [session.check_header("state", h) for h in (5, 6, 6, 4, 9, 10)]

    assert verdicts == [
        Verdict.APPLY,
        Verdict.APPLY,
        Verdict.DUPLICATE,
        Verdict.STALE,
        Verdict.APPLY,
        Verdict.APPLY,
    ]
    assert session.counters == {"duplicates": 1, "stale": 1, "gaps": 2}


def test_header_ids_are_counted_per_topic_and_survive_the_uint32_wrap() -> None:
    session = ProtocolSession()
    session.check_header("state", 2**32 - 1)
    session.check_header("visualization", 100)

    assert session.check_header("state", 0) is Verdict.APPLY
    assert session.check_header("visualization", 3) is Verdict.STALE


def test_a_new_online_accepts_header_ids_starting_again() -> None:
    session = ProtocolSession()
    session.check_header("state", 500)

    reconnected = session.on_connection("ONLINE", now=10.0)

    assert reconnected
    assert session.check_header("state", 0) is Verdict.APPLY


def test_a_retained_online_without_states_turns_unreachable_after_the_interval() -> None:
    session = ProtocolSession(state_interval=30.0)
    session.on_connection("ONLINE", now=0.0)

    assert session.link(now=30.0) is Link.ONLINE
    assert session.link(now=30.0 + TIMEOUT_GRACE + 0.1) is Link.UNREACHABLE


def test_a_frozen_vehicle_is_unreachable_after_its_declared_interval_plus_grace() -> None:
    # A vehicle whose factsheet declares a 10 s state interval and then freezes (radio loss,
    # SIGSTOP): control notices it from the missing states alone, long before the broker's
    # keepalive (22-29 s with Mosquitto 2.0) publishes its will.
    session = ProtocolSession(state_interval=10.0)
    session.on_connection("ONLINE", now=0.0)
    session.on_state(now=2.0, skew=None)

    assert session.link(now=2.0 + 10.0 + TIMEOUT_GRACE - 0.1) is Link.ONLINE
    assert session.link(now=2.0 + 10.0 + TIMEOUT_GRACE + 0.1) is Link.UNREACHABLE
    assert session.reported is Link.ONLINE  # what it said last: the verdict is ours


def test_a_vehicle_declaring_the_30_s_maximum_is_not_called_unreachable_before_it() -> None:
    session = ProtocolSession(state_interval=30.0)
    session.on_state(now=0.0, skew=None)

    assert session.link(now=29.9) is Link.ONLINE
    assert session.link(now=30.0 + TIMEOUT_GRACE) is Link.ONLINE


def test_a_state_revives_an_unreachable_vehicle_and_asks_for_reconciliation() -> None:
    session = ProtocolSession(state_interval=1.0)
    assert session.on_state(now=0.0, skew=0.2)  # first contact

    assert not session.on_state(now=1.0, skew=0.1)
    assert session.link(now=100.0) is Link.UNREACHABLE
    assert session.on_state(now=100.0, skew=0.1)
    assert session.link(now=100.5) is Link.ONLINE


def test_last_will_and_3_0_spellings() -> None:
    session = ProtocolSession()
    session.on_connection("ONLINE", now=0.0)

    assert not session.on_connection("CONNECTION_BROKEN", now=1.0)
    assert session.link(now=1.0) is Link.CONNECTIONBROKEN
    assert session.on_connection("ONLINE", now=2.0)
    session.on_connection("OFFLINE", now=3.0)
    assert session.link(now=3.0) is Link.OFFLINE
