"""The traffic-wait section of the report page and its CSV exports (reports.views calls these)."""

from typing import Any

from django.http import HttpRequest
from django.utils.safestring import mark_safe

from reports import charts, heatmap, wait_selectors
from reports.selectors import ReportFilter

WAIT_EXPORTS = {"waits_hourly", "waits_vehicles", "waits_nodes"}


def wait_context(request: HttpRequest, report: ReportFilter) -> dict[str, Any]:
    """Mean/p95 per hour (chart, hour-of-day table) and per vehicle, and the heatmap."""
    series = wait_selectors.mean_wait_series(report)
    chart = charts.columns(
        [round(mean, 1) for _, mean in series], [label for label, _ in series], part="wait"
    )
    count, seconds = wait_selectors.wait_totals(report)
    found = wait_selectors.wait_heatmap(report, map_id=request.GET.get("wait_map", ""))
    return {
        "wait_total": count,
        "wait_seconds": seconds,
        "wait_chart_svg": mark_safe(chart.svg("Mean traffic wait (s)")),  # noqa: S308  (escaped)
        "wait_hours_of_day": wait_selectors.waits_by_hour_of_day(report),
        "wait_vehicles": wait_selectors.waits_by_vehicle(report)[:100],
        "wait_heatmap": found,
        "wait_heatmap_svg": mark_safe(  # noqa: S308  (heatmap_svg escapes every text)
            heatmap.heatmap_svg(found, f"Traffic wait seconds per node on {found.map_id}")
        )
        if found
        else "",
    }


def wait_rows(name: str, report: ReportFilter) -> list[list[Any]]:
    """One of WAIT_EXPORTS as CSV rows (header first)."""
    if name == "waits_hourly":
        return [["hour", "waits", "wait_s", "mean_s", "p95"]] + [
            [moment.isoformat(), s.count, round(s.seconds, 1), _round(s.mean_s), s.p95]
            for moment, s in wait_selectors.waits_by_hour(report)
        ]
    if name == "waits_vehicles":
        return [["vehicle", "waits", "wait_s", "mean_s", "p95"]] + [
            [s.label, s.count, round(s.seconds, 1), _round(s.mean_s), s.p95]
            for s in wait_selectors.waits_by_vehicle(report)
        ]
    found = wait_selectors.wait_heatmap(report)
    return (
        [["map", "node", "x", "y", "waits", "wait_s"]]
        + [
            [found.map_id, h.node_id, h.x, h.y, h.count, round(h.seconds, 1)]
            for h in sorted(found.heat, key=lambda h: -h.seconds)
        ]
        if found
        else [["map", "node", "x", "y", "waits", "wait_s"]]
    )


def _round(value: float | None) -> float | str:
    return "" if value is None else round(value, 1)
