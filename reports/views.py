"""Report pages for managers and their CSV exports (thin: selectors compute, templates draw)."""

import csv
from datetime import timedelta
from typing import Any

from django import forms
from django.http import Http404, HttpRequest, HttpResponse
from django.shortcuts import render
from django.utils import timezone
from django.utils.safestring import SafeString, mark_safe

from fleet import roles
from fleet.access import require_permission
from reports import charts, selectors, wait_views
from reports.models import LEAD_TIME_BUCKETS
from reports.selectors import ReportFilter
from reports.services import TIME_COLUMNS
from robots.models import Vehicle

MAX_DAYS = 93
STATE_PARTS = [column.removesuffix("_s") for column in TIME_COLUMNS]


class ReportFilterForm(forms.Form):
    """Date range (default: the last 7 days) and optional vehicles."""

    start = forms.DateField(required=False, widget=forms.DateInput(attrs={"type": "date"}))
    end = forms.DateField(required=False, widget=forms.DateInput(attrs={"type": "date"}))
    vehicles = forms.ModelMultipleChoiceField(Vehicle.objects.all(), required=False)

    def clean(self) -> dict[str, Any]:
        data = super().clean() or {}
        today = timezone.localdate()
        data["end"] = data.get("end") or today
        data["start"] = data.get("start") or data["end"] - timedelta(days=6)
        if data["start"] > data["end"]:
            raise forms.ValidationError("The start date is after the end date.")
        if (data["end"] - data["start"]).days >= MAX_DAYS:
            raise forms.ValidationError(f"Choose at most {MAX_DAYS} days.")
        return data

    def report(self) -> ReportFilter:
        data = self.cleaned_data
        ids = tuple(vehicle.pk for vehicle in data.get("vehicles") or [])
        return ReportFilter(data["start"], data["end"], ids)


def _read_filter(request: HttpRequest) -> tuple[ReportFilterForm, ReportFilter | None]:
    """The form bound to the query string (empty = defaults) and its filter, None if invalid."""
    form = ReportFilterForm(request.GET or {})
    return form, form.report() if form.is_valid() else None


@require_permission(roles.VIEW_REPORTS)
def report_page(request: HttpRequest) -> HttpResponse:
    """Throughput, lead times, punctuality, utilisation and errors over a date range."""
    form, report = _read_filter(request)
    if report is None:
        return render(request, "reports/report.html", {"form": form}, status=400)
    hours = selectors.throughput_by_hour(report)
    uses = selectors.utilisation(report)
    stages = selectors.lead_times(report)
    profile = charts.columns(
        selectors.hour_of_day_profile(hours), [f"{hour}h" for hour in range(24)]
    )
    bands = [selectors.bucket_label(i) for i in range(len(stages[-1].counts))]
    states = charts.stacked_columns(
        [{part: use.share(f"{part}_s") * 100 for part in STATE_PARTS} for use in uses],
        [use.vehicle for use in uses],
        STATE_PARTS,
        max_labels=40,
        top=100,
    )
    context = {
        "form": form,
        "report": report,
        "query": request.GET.urlencode(),
        "throughput_svg": _svg(_throughput_chart(hours), "Orders finished and failed"),
        "profile_svg": _svg(profile, "Average orders finished per hour of the day"),
        "finished_total": sum(p.finished for p in hours),
        "failed_total": sum(p.failed for p in hours),
        "shifts": selectors.throughput_by_shift(hours),
        "punctuality": selectors.punctuality(hours),
        "stages": stages,
        "lead_time_svg": _svg(charts.columns(stages[-1].counts, bands), "Order lead times"),
        "uses": uses,
        "utilisation_svg": _svg(states, "Share of time per state and vehicle"),
        "errors": selectors.errors(report)[:50],
    } | wait_views.wait_context(request, report)
    return render(request, "reports/report.html", context)


def _svg(chart: charts.Chart, label: str) -> SafeString:
    return mark_safe(chart.svg(label))  # noqa: S308  (Chart.svg escapes every text)


def _throughput_chart(hours: list[selectors.HourPoint]) -> charts.Chart:
    """Per hour for up to three days, per day beyond (the CSV always has every hour)."""
    if len(hours) <= 72:
        values: list[dict[str, float]] = [
            {"finished": p.finished, "failed": p.failed} for p in hours
        ]
        return charts.stacked_columns(
            values, [f"{p.hour:%d.%m. %H}h" for p in hours], ["finished", "failed"]
        )
    days = selectors.throughput_by_day(hours)
    return charts.stacked_columns(
        [{"finished": float(d.finished), "failed": float(d.failed)} for d in days],
        [f"{d.day:%d.%m.}" for d in days],
        ["finished", "failed"],
    )


EXPORTS = {"throughput", "shifts", "lead_times", "utilisation", "errors"} | wait_views.WAIT_EXPORTS


@require_permission(roles.VIEW_REPORTS)
def export_csv(request: HttpRequest, name: str) -> HttpResponse:
    """One report table as CSV, for the same filter as the page."""
    if name not in EXPORTS:
        raise Http404(f"no report named {name!r}")
    form, report = _read_filter(request)
    if report is None:
        return HttpResponse(form.errors.as_text(), status=400, content_type="text/plain")
    response = HttpResponse(content_type="text/csv; charset=utf-8")
    filename = f"{name}_{report.start}_{report.end}.csv"
    response["Content-Disposition"] = f'attachment; filename="{filename}"'
    writer = csv.writer(response)
    for row in _rows(name, report):
        writer.writerow(row)
    return response


def _rows(name: str, report: ReportFilter) -> list[list[Any]]:
    if name in wait_views.WAIT_EXPORTS:
        return wait_views.wait_rows(name, report)
    if name == "throughput":
        points = selectors.throughput_by_hour(report)
        return [["hour", "finished", "failed", "cancelled"]] + [
            [p.hour.isoformat(), p.finished, p.failed, p.cancelled] for p in points
        ]
    if name == "shifts":
        rows = selectors.throughput_by_shift(selectors.throughput_by_hour(report))
        return [["day", "shift", "finished", "failed"]] + [
            [r.day.isoformat(), r.shift, r.finished, r.failed] for r in rows
        ]
    if name == "lead_times":
        header = ["stage", "orders", "mean_s", "p50", "p90"]
        buckets = [selectors.bucket_label(i) for i in range(len(LEAD_TIME_BUCKETS) + 1)]
        return [header + buckets] + [
            [s.stage, s.count, _round(s.mean_s), s.percentile(0.5), s.percentile(0.9), *s.counts]
            for s in selectors.lead_times(report)
        ]
    if name == "utilisation":
        header = ["vehicle", *TIME_COLUMNS, "distance_m", "energy_pct", "finished"]
        return [header] + [
            [u.vehicle, *(round(u.seconds[c]) for c in TIME_COLUMNS)]
            + [round(u.distance_m, 1), round(u.energy_pct, 1), u.finished]
            for u in selectors.utilisation(report)
        ]
    return [["vehicle", "error_type", "count"]] + [
        [e.vehicle, e.error_type, e.count] for e in selectors.errors(report)
    ]


def _round(value: float | None) -> float | str:
    return "" if value is None else round(value, 1)
