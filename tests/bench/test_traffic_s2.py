"""The S2 benchmark's plumbing: grid rules, a run measured in hours, delays (short runs)."""

from bench.traffic import scenarios


def test_a_short_s2_run_under_grid_rules_reports_errands_without_a_share() -> None:
    out = scenarios.s2(
        quick=True, seed=1, instances=["MR23-I-04"], switch_push=scenarios.SWITCH_PUSH,
        congestion=scenarios.S2_CONGESTION, grid_rules=True, hours=0.01, delays=True,
    )  # fmt: skip
    assert out["grid_rules"] is True
    assert out["delays"] == "5% of moves +5-30 s"
    assert out["i04_steps"] == 36
    assert out["i04_errands"] > 0
    assert out["i04_best_known"] is None  # 36 steps are not the instance's 500
    assert out["i04_share_of_best"] is None
    assert out["i04_collisions"] == 0
    assert out["i04_deadlocks_wait_cycles"] == 0
    assert out["i04_stall_chains"] == []
