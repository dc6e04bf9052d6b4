"""Idempotency keys of API requests: claim before the request runs, complete with its response.

The protocol (see `orders.api.idempotency` for the view side):
1. `claim_idempotency_key` in autocommit: a new key is inserted IN_FLIGHT and committed at once,
   so a concurrent retry finds it and gets 409; a completed key with the same request returns
   the stored response; the same key with a different request is refused with 422.
2. The request runs in a transaction that ends with `complete_idempotency_key`, so the order and
   the stored response commit together or not at all.
3. If the request fails, `release_idempotency_key` deletes the claim and a retry runs afresh.
   A claim whose request died without releasing it (a killed process) counts as abandoned once
   it is older than FLEET_ORDERS IDEMPOTENCY_STALE_AFTER and may be claimed again.
"""

from dataclasses import dataclass
from datetime import datetime, timedelta
from typing import Any

from django.contrib.auth.models import User
from django.db import IntegrityError, transaction
from django.utils import timezone

from fleet.exceptions import DomainError, InvalidRequestError
from orders.conf import setting
from orders.models import IdempotencyKey

State = IdempotencyKey.State


class IdempotencyKeyInFlight(DomainError):
    """The first request with this key has not finished yet (HTTP 409; retry later)."""


class IdempotencyKeyReused(InvalidRequestError):
    """The key was used before with a different request (HTTP 422)."""


@dataclass(frozen=True)
class StoredResponse:
    """The response of the completed first request, to replay."""

    status: int
    body: Any


def claim_idempotency_key(
    *, user: User, key: str, request_hash: str, path: str
) -> IdempotencyKey | StoredResponse:
    """Claim `key` for a request, or return the response stored for it. Call in autocommit."""
    now = timezone.now()
    try:
        with transaction.atomic():
            return IdempotencyKey.objects.create(
                user=user, key=key, request_hash=request_hash, request_path=path, locked_at=now
            )
    except IntegrityError:
        pass
    existing = IdempotencyKey.objects.filter(user=user, key=key).first()
    if existing is None:  # released between our insert and this read
        raise IdempotencyKeyInFlight("a request with this Idempotency-Key is in progress")
    if existing.request_hash != request_hash:
        raise IdempotencyKeyReused("this Idempotency-Key was used for a different request")
    if existing.state == State.COMPLETED:
        return StoredResponse(existing.response_status or 200, existing.response_body)
    if _take_over_abandoned(existing, now):
        return existing
    raise IdempotencyKeyInFlight("a request with this Idempotency-Key is in progress")


def _take_over_abandoned(claim: IdempotencyKey, now: datetime) -> bool:
    stale = now - timedelta(seconds=float(setting("IDEMPOTENCY_STALE_AFTER")))
    if claim.locked_at >= stale:
        return False
    taken = IdempotencyKey.objects.filter(
        pk=claim.pk, state=State.IN_FLIGHT, locked_at=claim.locked_at
    ).update(locked_at=now)
    claim.locked_at = now
    return bool(taken)


def complete_idempotency_key(*, claim: IdempotencyKey, status: int, body: Any) -> None:
    """Store the response of the claimed request; call in the request's transaction."""
    claim.state, claim.response_status, claim.response_body = State.COMPLETED, status, body
    claim.completed_at = timezone.now()
    claim.save(update_fields=["state", "response_status", "response_body", "completed_at"])


def release_idempotency_key(*, claim: IdempotencyKey) -> None:
    """Forget a claim whose request failed, so that a retry runs it again."""
    IdempotencyKey.objects.filter(
        pk=claim.pk, state=State.IN_FLIGHT, locked_at=claim.locked_at
    ).delete()


def prune_idempotency_keys(*, now: datetime | None = None) -> int:
    """Delete keys older than FLEET_ORDERS IDEMPOTENCY_TTL; returns how many."""
    cutoff = (now or timezone.now()) - timedelta(seconds=float(setting("IDEMPOTENCY_TTL")))
    deleted, _ = IdempotencyKey.objects.filter(created_at__lt=cutoff).delete()
    return deleted
