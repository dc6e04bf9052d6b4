"""Integration clients and their API tokens."""

import hashlib
import secrets
from collections.abc import Collection
from datetime import datetime, timedelta

from django.contrib.auth import get_user_model
from django.db import transaction
from django.utils import timezone

from fleet import roles
from fleet.exceptions import InvalidRequestError
from orders.models import ApiToken, IntegrationClient

TOKEN_PREFIX = "oft_"  # noqa: S105 (not a secret) marks a key as an Open Fleet token (secret scanners can look for it)
_TOUCH_EVERY = timedelta(minutes=1)  # last_used_at is written at most this often


@transaction.atomic
def create_integration_client(
    *, name: str, description: str = "", scopes: Collection[str] = ()
) -> IntegrationClient:
    """Register a client with its own (password-less) user, under which its requests run. Its
    tokens may call the endpoints of `scopes` only (none by default: grant what it needs)."""
    if IntegrationClient.objects.filter(name=name).exists():
        raise InvalidRequestError(f"a client named {name!r} exists")
    user = get_user_model().objects.create_user(username=f"client:{name}"[:150])
    user.set_unusable_password()
    user.save(update_fields=["password"])
    return IntegrationClient.objects.create(
        name=name, user=user, description=description, scopes=checked_scopes(scopes)
    )


def checked_scopes(scopes: Collection[str]) -> list[str]:
    """`scopes` in the order of `fleet.roles.API_SCOPES`; an unknown one is refused."""
    unknown = sorted(set(scopes) - set(roles.ALL_API_SCOPES))
    if unknown:
        raise InvalidRequestError(f"unknown scopes: {', '.join(unknown)}")
    return [scope for scope in roles.ALL_API_SCOPES if scope in scopes]


def issue_api_token(
    *, client: IntegrationClient, expires_at: datetime | None = None
) -> tuple[ApiToken, str]:
    """Create a token for `client`; returns it with the key, which is not stored and shown once."""
    key = TOKEN_PREFIX + secrets.token_urlsafe(32)
    token = ApiToken.objects.create(
        client=client, key_hash=hash_key(key), prefix=key[:12], expires_at=expires_at
    )
    return token, key


def revoke_api_token(*, token: ApiToken) -> None:
    """Stop accepting `token` from now on."""
    if token.revoked_at is None:
        token.revoked_at = timezone.now()
        token.save(update_fields=["revoked_at"])


def authenticate_api_token(*, key: str) -> ApiToken | None:
    """The valid token with this key (client active, not revoked or expired), or None. Notes when
    it was last used, at most once a minute so requests do not each write a row."""
    now = timezone.now()
    token = (
        ApiToken.objects.select_related("client__user")
        .filter(key_hash=hash_key(key), revoked_at__isnull=True, client__is_active=True)
        .first()
    )
    if token is None or (token.expires_at is not None and token.expires_at <= now):
        return None
    if token.last_used_at is None or now - token.last_used_at > _TOUCH_EVERY:
        ApiToken.objects.filter(pk=token.pk).update(last_used_at=now)
    return token


def hash_key(key: str) -> str:
    """What is stored of a key: its SHA-256 (keys are long and random, so no salt is needed)."""
    return hashlib.sha256(key.encode()).hexdigest()
