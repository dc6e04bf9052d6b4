"""The audit trail page and its CSV export (staff with the view permission only)."""

import csv
import itertools
from datetime import datetime, time, timedelta

from django import forms
from django.core.paginator import Paginator
from django.db.models import Q, QuerySet
from django.http import HttpRequest, HttpResponse, StreamingHttpResponse
from django.shortcuts import render
from django.utils import timezone

from fleet import roles
from fleet.access import require_permission
from fleet.models import AuditEntry


class AuditSearchForm(forms.Form):
    q = forms.CharField(
        required=False, label="Search", help_text="actor, action, target or address"
    )
    action = forms.CharField(required=False)
    start = forms.DateField(required=False, widget=forms.DateInput(attrs={"type": "date"}))
    end = forms.DateField(required=False, widget=forms.DateInput(attrs={"type": "date"}))

    def entries(self) -> QuerySet[AuditEntry]:
        entries = AuditEntry.objects.all()
        data = self.cleaned_data
        if data.get("q"):
            term = data["q"]
            entries = entries.filter(
                Q(actor__icontains=term)
                | Q(action__icontains=term)
                | Q(target_id__icontains=term)
                | Q(target_type__icontains=term)
                | Q(source__icontains=term)
            )
        if data.get("action"):
            entries = entries.filter(action__startswith=data["action"])
        if data.get("start"):
            entries = entries.filter(
                at__gte=timezone.make_aware(datetime.combine(data["start"], time.min))
            )
        if data.get("end"):
            end = datetime.combine(data["end"] + timedelta(days=1), time.min)
            entries = entries.filter(at__lt=timezone.make_aware(end))
        return entries


@require_permission(roles.VIEW_AUDIT)
def audit_page(request: HttpRequest) -> HttpResponse:
    form = AuditSearchForm(request.GET or {})
    if not form.is_valid():
        return render(request, "fleet/audit.html", {"form": form}, status=400)
    page = Paginator(form.entries(), 100).get_page(request.GET.get("page"))
    query = request.GET.copy()
    query.pop("page", None)
    return render(
        request, "fleet/audit.html", {"form": form, "page": page, "query": query.urlencode()}
    )


class _Echo:
    def write(self, value: str) -> str:
        return value


@require_permission(roles.VIEW_AUDIT)
def audit_csv(request: HttpRequest) -> HttpResponse | StreamingHttpResponse:
    """Every matching entry as CSV, streamed (the trail can be long)."""
    form = AuditSearchForm(request.GET or {})
    if not form.is_valid():
        return HttpResponse(form.errors.as_text(), status=400, content_type="text/plain")
    writer = csv.writer(_Echo())
    header = ["at", "actor", "source", "action", "target_type", "target_id", "detail"]
    rows = (
        [e.at.isoformat(), e.actor, e.source, e.action, e.target_type, e.target_id, e.detail]
        for e in form.entries().iterator(chunk_size=2000)
    )
    lines = (writer.writerow(row) for row in itertools.chain([header], rows))
    response = StreamingHttpResponse(lines, content_type="text/csv; charset=utf-8")
    response["Content-Disposition"] = 'attachment; filename="audit.csv"'
    return response
