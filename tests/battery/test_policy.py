"""The charging policy, the consumption model and charger assignment as pure logic."""

import pytest

from battery.planning import ChargePoint, ChargeRequest, assign_points
from battery.policy import Band, Consumption, Levels, Reason

LEVELS = Levels(critical=15, needs_charge=30, sufficient=60, charge_until=90, full=98)


@pytest.mark.parametrize(
    ("charge", "band"),
    [
        (10, Band.CRITICAL),
        (15, Band.NEEDS_CHARGE),
        (29.9, Band.NEEDS_CHARGE),
        (30, Band.WORKING),
        (60, Band.SUFFICIENT),
        (98, Band.FULL),
    ],
)
def test_bands(charge: float, band: Band) -> None:
    assert LEVELS.band(charge) is band


def test_the_shift_reserve_raises_the_working_minimum_by_the_learned_consumption() -> None:
    shift = Levels(critical=15, needs_charge=30, sufficient=60, shift_reserve_hours=2)
    assert shift.working_minimum(drain_per_hour=None) == 30  # nothing learned: needs_charge
    assert shift.working_minimum(drain_per_hour=10) == 35  # 15 + 2 h × 10 %/h
    assert shift.working_minimum(drain_per_hour=40) == 60  # never above sufficient
    assert shift.band(33, drain_per_hour=10) is Band.NEEDS_CHARGE


def test_who_goes_charging_and_why() -> None:
    assert LEVELS.charge_reason(10, idle=True, work_waiting=True) is Reason.CRITICAL
    assert LEVELS.charge_reason(25, idle=True, work_waiting=True) is Reason.LOW
    assert LEVELS.charge_reason(25, idle=False, work_waiting=True) is None  # finishes its job
    assert LEVELS.charge_reason(70, idle=True, work_waiting=False) is Reason.OPPORTUNITY
    assert LEVELS.charge_reason(70, idle=True, work_waiting=True) is None
    assert LEVELS.charge_reason(85, idle=True, work_waiting=False) is None  # above 80
    off = Levels(opportunity_charging=False)
    assert off.charge_reason(50, idle=True, work_waiting=False) is None


def test_when_charging_stops() -> None:
    assert LEVELS.stop_charging(90, work_waiting=False, queue_waiting=False)
    assert not LEVELS.stop_charging(70, work_waiting=False, queue_waiting=False)
    assert LEVELS.stop_charging(60, work_waiting=True, queue_waiting=False)
    assert LEVELS.stop_charging(60, work_waiting=False, queue_waiting=True)
    assert not LEVELS.stop_charging(50, work_waiting=True, queue_waiting=True)


def test_a_job_is_refused_when_the_projected_charge_would_fall_below_critical() -> None:
    assert LEVELS.job_refusal(40, 5) is None
    assert "drop to 14%" in (LEVELS.job_refusal(40, 26) or "")
    assert "needs charge" in (LEVELS.job_refusal(29, 1) or "")
    assert LEVELS.job_refusal(None, 100) is None


def test_consumption_is_learned_per_metre_and_per_standing_hour() -> None:
    model = Consumption()
    for _ in range(30):
        model.observe(used=1.0, metres=0.0, seconds=600)  # 6 %/h standing
    assert model.per_hour == pytest.approx(6.0, rel=0.01)
    for _ in range(30):
        model.observe(used=3.0 + 0.1, metres=100.0, seconds=60)  # 0.1 standing + 3 driving
    assert model.per_metre == pytest.approx(0.03, rel=0.01)
    assert model.project(metres=100, standing_seconds=600) == pytest.approx(4.0, rel=0.02)


def test_too_short_observations_teach_nothing() -> None:
    model = Consumption()
    model.observe(used=1.0, metres=1.0, seconds=10)
    model.observe(used=-3.0, metres=50.0, seconds=100)  # charging mixed in
    assert (model.per_metre, model.per_hour) == (None, None)


def distances(table: dict[str, dict[str, float]]):  # type: ignore[no-untyped-def]
    return lambda goal: table[goal]


def test_points_go_to_the_most_urgent_then_nearest_and_the_rest_queue() -> None:
    points = [ChargePoint(1, 0, "C1"), ChargePoint(2, 0, "C2")]
    table = {"C1": {"a": 1.0, "b": 5.0, "c": 2.0}, "C2": {"a": 9.0, "b": 3.0, "c": 8.0}}
    requests = [
        ChargeRequest(10, "a", 50, Reason.OPPORTUNITY),
        ChargeRequest(11, "b", 25, Reason.LOW),
        ChargeRequest(12, "c", 12, Reason.CRITICAL),
    ]

    plan = assign_points(requests, points, distances(table))

    assert [(r.key, p.charger) for r, p, _ in plan.assigned] == [(12, 1), (11, 2)]
    assert plan.queue == {10: 1}


def test_a_point_takes_only_compatible_vehicle_types() -> None:
    points = [ChargePoint(1, 0, "C1", frozenset({"big"}))]
    plan = assign_points(
        [ChargeRequest(1, "a", 10, Reason.CRITICAL, vehicle_type="small")],
        points,
        distances({"C1": {"a": 1.0}}),
    )
    assert plan.assigned == []
    assert plan.queue == {1: 1}
