"""Raise, deduplicate, acknowledge and resolve alerts."""

import logging
from collections.abc import Collection, Mapping
from typing import Any

from django.contrib.auth.models import AbstractBaseUser, AnonymousUser
from django.db import IntegrityError, transaction
from django.db.models import F, Q
from django.utils import timezone

from alerts.models import SEVERITY_RANK, Alert, Severity, Source
from fleet.exceptions import DomainError, InvalidRequestError
from robots.models import Vehicle

logger = logging.getLogger(__name__)

User = AbstractBaseUser | AnonymousUser


def _vehicle_id(vehicle: Vehicle | int | None) -> int | None:
    return vehicle.pk if isinstance(vehicle, Vehicle) else vehicle


def raise_alert(
    *,
    cause: str,
    severity: str = Severity.WARNING,
    message: str,
    source: str = Source.OTHER,
    vehicle: Vehicle | int | None = None,
    order_ref: str = "",
    details: Mapping[str, Any] | None = None,
) -> Alert:
    """Open an alert for `cause`, or refresh the one already open for it (one per cause).

    `cause` is a stable key of what is wrong (e.g. ``battery:12``, ``order_failed:ERP-7``); the
    same cause raised again bumps `occurrences` and `last_seen_at`, takes the newer message and
    raises (never lowers) the severity. Safe under concurrency: the partial unique index
    decides which of two racing creators wins, the loser refreshes the winner's row.
    """
    if severity not in SEVERITY_RANK:
        raise InvalidRequestError(f"unknown severity {severity!r}")
    if source not in Source.values:
        raise InvalidRequestError(f"unknown alert source {source!r}")
    if not cause:
        raise InvalidRequestError("an alert needs a cause key")
    cause = cause[:200]
    for _attempt in range(3):
        with transaction.atomic():
            alert = (
                Alert.objects.select_for_update()
                .filter(cause=cause)
                .exclude(status=Alert.Status.RESOLVED)
                .first()
            )
            if alert is not None:
                alert.occurrences = F("occurrences") + 1
                alert.last_seen_at = timezone.now()
                alert.message = message
                if SEVERITY_RANK[severity] > SEVERITY_RANK[alert.severity]:
                    alert.severity = severity
                if details is not None:
                    alert.details = dict(details)
                alert.save(
                    update_fields=["occurrences", "last_seen_at", "message", "severity", "details"]
                )
                alert.refresh_from_db(fields=["occurrences"])
                return alert
            try:
                with transaction.atomic():
                    return Alert.objects.create(
                        cause=cause,
                        source=source,
                        severity=severity,
                        vehicle_id=_vehicle_id(vehicle),
                        order_ref=order_ref[:100],
                        message=message,
                        details=dict(details or {}),
                    )
            except IntegrityError:
                # Another process opened it between our read and our insert: refresh theirs.
                continue
    raise DomainError(f"could not raise alert {cause!r}")  # pragma: no cover


def resolve_alert(
    cause: str, *, user: User | None = None, comment: str = "", auto: bool | None = None
) -> Alert | None:
    """Resolve the open alert of `cause` (no-op if none is open). Without a user it counts as
    auto-resolved: the cause cleared by itself."""
    now = timezone.now()
    with transaction.atomic():
        alert = (
            Alert.objects.select_for_update()
            .filter(cause=cause)
            .exclude(status=Alert.Status.RESOLVED)
            .first()
        )
        if alert is None:
            return None
        _close(
            alert, now=now, user=user, comment=comment, auto=user is None if auto is None else auto
        )
        return alert


def _close(alert: Alert, *, now: Any, user: User | None, comment: str, auto: bool) -> None:
    alert.status = Alert.Status.RESOLVED
    alert.resolved_at = now
    alert.resolved_by = user if user is not None and user.is_authenticated else None  # type: ignore[assignment]
    alert.resolve_comment = comment
    alert.auto_resolved = auto
    alert.save(
        update_fields=["status", "resolved_at", "resolved_by", "resolve_comment", "auto_resolved"]
    )


def acknowledge_alert(*, alert_id: int, user: User, comment: str = "") -> Alert:
    """A person takes ownership of an open alert; stops its escalation."""
    with transaction.atomic():
        alert = Alert.objects.select_for_update().filter(pk=alert_id).first()
        if alert is None:
            raise DomainError(f"no alert {alert_id}")
        if alert.status != Alert.Status.OPEN:
            raise DomainError(f"alert {alert_id} is {alert.get_status_display()}")
        alert.status = Alert.Status.ACKNOWLEDGED
        alert.acknowledged_at = timezone.now()
        alert.acknowledged_by = user if user.is_authenticated else None  # type: ignore[assignment]
        alert.acknowledge_comment = comment
        alert.save(
            update_fields=["status", "acknowledged_at", "acknowledged_by", "acknowledge_comment"]
        )
        return alert


def resolve_by_user(*, alert_id: int, user: User, comment: str) -> Alert:
    """A person closes an alert with a comment saying what was done."""
    if not comment.strip():
        raise InvalidRequestError("say what was done: a comment is required to resolve")
    with transaction.atomic():
        alert = Alert.objects.select_for_update().filter(pk=alert_id).first()
        if alert is None:
            raise DomainError(f"no alert {alert_id}")
        if alert.status == Alert.Status.RESOLVED:
            raise DomainError(f"alert {alert_id} is already resolved")
        _close(alert, now=timezone.now(), user=user, comment=comment.strip(), auto=False)
        return alert


def sync_causes(
    *,
    prefixes: Collection[str],
    active: Mapping[str, Mapping[str, Any]],
    scope: set[str] | frozenset[str] | None = None,
) -> tuple[int, int]:
    """Make the open alerts under `prefixes` match `active` (cause -> raise_alert kwargs).

    Raises every active cause not yet open, auto-resolves every open cause under a prefix that
    is no longer active; an open alert whose cause got worse takes the higher severity.
    `scope` (cause keys such as ``battery:12``, covering themselves and ``battery:12:...`` but
    not ``battery:123``) limits which open alerts may be resolved, for callers that saw only
    part of the fleet. Costs one query when nothing changed. Returns (raised, resolved).
    """
    open_causes = dict(
        Alert.objects.exclude(status=Alert.Status.RESOLVED)
        .filter(_starts_with_any(prefixes))
        .values_list("cause", "severity")
    )
    # New causes in one INSERT and cleared ones in one UPDATE: after a broker restart every
    # vehicle raises (or clears) at once, and one savepoint + select + insert per alert took
    # seconds (issue 11, docs/LOAD.md).
    raised = _open_many({c: kw for c, kw in active.items() if c not in open_causes})
    for cause, kwargs in active.items():
        severity = open_causes.get(cause)
        if (
            severity is not None
            and SEVERITY_RANK[kwargs.get("severity", Severity.WARNING)] > SEVERITY_RANK[severity]
        ):
            raise_alert(cause=cause, **kwargs)  # worse now: the open alert takes the severity
    cleared = [
        cause
        for cause in set(open_causes) - set(active)
        if scope is None or _in_scope(cause, scope)
    ]
    return raised, _auto_resolve_many(cleared)


BULK_ROWS = 500  # rows per INSERT / causes per UPDATE


def _open_many(causes: Mapping[str, Mapping[str, Any]]) -> int:
    """Open an alert for each cause (none is open yet, as the caller just read): one INSERT
    per BULK_ROWS. A cause another process opened meanwhile is skipped by the partial unique
    index (ON CONFLICT DO NOTHING): its alert is open, which is what was asked."""
    rows = []
    for cause, kwargs in causes.items():
        severity = kwargs.get("severity", Severity.WARNING)
        source = kwargs.get("source", Source.OTHER)
        if severity not in SEVERITY_RANK:
            raise InvalidRequestError(f"unknown severity {severity!r}")
        if source not in Source.values:
            raise InvalidRequestError(f"unknown alert source {source!r}")
        if not cause:
            raise InvalidRequestError("an alert needs a cause key")
        rows.append(
            Alert(
                cause=cause[:200],
                source=source,
                severity=severity,
                vehicle_id=_vehicle_id(kwargs.get("vehicle")),
                order_ref=str(kwargs.get("order_ref") or "")[:100],
                message=kwargs["message"],
                details=dict(kwargs.get("details") or {}),
            )
        )
    if rows:
        with transaction.atomic():
            Alert.objects.bulk_create(rows, batch_size=BULK_ROWS, ignore_conflicts=True)
    return len(rows)


def _auto_resolve_many(causes: list[str]) -> int:
    """Auto-resolve the open alerts of `causes` (their cause cleared by itself)."""
    resolved = 0
    now = timezone.now()
    for start in range(0, len(causes), BULK_ROWS):
        resolved += (
            Alert.objects.filter(cause__in=causes[start : start + BULK_ROWS])
            .exclude(status=Alert.Status.RESOLVED)
            .update(
                status=Alert.Status.RESOLVED,
                resolved_at=now,
                resolved_by=None,
                resolve_comment="",
                auto_resolved=True,
            )
        )
    return resolved


def _in_scope(cause: str, scope: Collection[str]) -> bool:
    head = cause
    while head:
        if head in scope:
            return True
        head = head.rpartition(":")[0]
    return False


def _starts_with_any(prefixes: Collection[str]) -> Q:
    query = Q(pk__in=[])  # matches nothing when there are no prefixes
    for prefix in prefixes:
        query |= Q(cause__startswith=prefix)
    return query
