"""The protocol session: header ids per topic, liveness from states, reconnects."""

from control.session import PROBE_GRACE, TIMEOUT_GRACE, Link, ProtocolSession, Verdict


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


def _silent_since(at: float, state_interval: float = 30.0) -> ProtocolSession:
    session = ProtocolSession(state_interval=state_interval)
    session.on_connection("ONLINE", now=0.0)
    session.on_state(now=at, skew=None)
    return session


def test_a_silent_vehicle_is_probed_once_and_unreachable_when_it_does_not_answer() -> None:
    # Declares the 30 s maximum: without the probe it would count as ONLINE until 35 s.
    session = _silent_since(2.0)

    assert not session.probe_due(now=12.0, after=10.0)
    assert session.probe_due(now=12.1, after=10.0)
    session.on_probe(now=12.1, grace=PROBE_GRACE)

    assert not session.probe_due(now=13.0, after=10.0)  # one probe per silence episode
    assert session.link(now=12.1 + PROBE_GRACE - 0.1) is Link.ONLINE
    assert session.link(now=12.1 + PROBE_GRACE + 0.1) is Link.UNREACHABLE
    assert not session.probe_due(now=30.0, after=10.0)  # nor again while unreachable


def test_an_answer_to_the_probe_keeps_it_online_and_starts_a_new_episode() -> None:
    session = _silent_since(2.0)
    session.on_probe(now=12.5, grace=5.0)

    assert not session.on_state(now=13.0, skew=None)  # answered in time: no reconciliation
    assert session.link(now=18.0) is Link.ONLINE
    assert not session.probe_due(now=22.9, after=10.0)
    assert session.probe_due(now=23.1, after=10.0)  # silent again: a new probe


def test_an_online_message_ends_the_silence_episode_too() -> None:
    session = _silent_since(2.0)
    session.on_probe(now=12.5, grace=5.0)

    session.on_connection("ONLINE", now=14.0)

    assert session.link(now=20.0) is Link.ONLINE


def test_a_late_answer_revives_the_vehicle_and_asks_for_reconciliation() -> None:
    session = _silent_since(2.0)
    session.on_probe(now=12.5, grace=5.0)
    assert session.link(now=18.0) is Link.UNREACHABLE

    assert session.on_state(now=19.0, skew=None)
    assert session.link(now=19.0) is Link.ONLINE


def test_no_probe_when_off_or_when_its_own_interval_is_as_quick() -> None:
    assert _silent_since(0.0).probe_due(now=20.0, after=10.0)
    assert not _silent_since(0.0).probe_due(now=20.0, after=0.0)
    quick = _silent_since(0.0, state_interval=10.0)
    assert not quick.probe_due(now=12.0, after=10.0)
    assert quick.link(now=15.1) is Link.UNREACHABLE  # its state timeout: 10 s + grace


def test_no_probe_for_a_vehicle_that_is_not_online() -> None:
    unknown = ProtocolSession()
    assert not unknown.probe_due(now=60.0, after=10.0)
    broken = _silent_since(0.0)
    broken.on_connection("CONNECTIONBROKEN", now=1.0)
    assert not broken.probe_due(now=60.0, after=10.0)


def test_a_hibernating_vehicle_is_not_probed_until_it_wakes_up() -> None:
    session = _silent_since(2.0)
    session.on_connection("HIBERNATING", now=3.0)

    assert not session.probe_due(now=20.0, after=10.0)
    assert session.link(now=20.0) is Link.ONLINE

    session.on_connection("ONLINE", now=25.0)
    assert session.probe_due(now=35.1, after=10.0)
