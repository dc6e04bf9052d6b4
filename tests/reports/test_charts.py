"""Chart geometry and SVG markup (pure)."""

import pytest

from reports import charts


@pytest.mark.parametrize(
    ("value", "axis"), [(0, 1), (0.3, 0.5), (7, 10), (10, 10), (101, 200), (1234, 2000)]
)
def test_the_axis_maximum_is_a_round_number_at_or_above_the_highest_value(value, axis) -> None:
    assert charts.nice_maximum(value) == pytest.approx(axis)


def test_stacked_columns_stay_inside_the_plot_and_keep_their_order() -> None:
    chart = charts.stacked_columns(
        [{"busy": 60, "idle": 40.0001}, {"busy": 10}], ["a", "b"], ["busy", "idle"], top=100
    )
    busy_a, idle_a, busy_b = chart.rects
    assert (busy_a.part, idle_a.part, busy_b.part) == ("busy", "idle", "busy")
    assert idle_a.y + idle_a.height == pytest.approx(busy_a.y)  # stacked on top
    assert min(r.y for r in chart.rects) >= charts.TOP - 1e-6
    assert busy_b.height == pytest.approx(busy_a.height / 6)


def test_every_text_in_the_svg_is_escaped() -> None:
    svg = charts.columns([1], ['<script>alert("x")</script>']).svg('a "label" & more')
    assert "<script>" not in svg
    assert "&lt;script&gt;" in svg
    assert 'aria-label="a &quot;label&quot; &amp; more"' in svg
