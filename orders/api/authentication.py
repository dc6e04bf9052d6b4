"""Token authentication of integration clients: `Authorization: Bearer <key>` (or `Token <key>`).

The request runs as the client's user; `request.auth` is the `ApiToken`. Browsers keep using
the session (see REST_FRAMEWORK in settings).
"""

from typing import Any

from django.contrib.auth.base_user import AbstractBaseUser
from drf_spectacular.extensions import OpenApiAuthenticationExtension
from rest_framework import authentication, exceptions
from rest_framework.request import Request

from orders.models import ApiToken


class ClientTokenAuthentication(authentication.BaseAuthentication):
    """Authenticates requests carrying an integration client's API token."""

    keywords = (b"bearer", b"token")

    def authenticate(self, request: Request) -> tuple[AbstractBaseUser, ApiToken] | None:
        parts = authentication.get_authorization_header(request).split()
        if not parts or parts[0].lower() not in self.keywords:
            return None
        if len(parts) != 2:
            raise exceptions.AuthenticationFailed("Give the token after the keyword, no spaces.")
        try:
            key = parts[1].decode("ascii")
        except UnicodeDecodeError:
            raise exceptions.AuthenticationFailed("Invalid token.") from None
        from orders import services  # not at import: DRF loads this module while it starts up

        token = services.authenticate_api_token(key=key)
        if token is None:
            raise exceptions.AuthenticationFailed("Invalid, expired or revoked token.")
        return token.client.user, token

    def authenticate_header(self, request: Request) -> str:
        """Makes unauthenticated requests 401 with a challenge (rather than 403)."""
        return 'Bearer realm="api"'


class ClientTokenScheme(OpenApiAuthenticationExtension):  # type: ignore[no-untyped-call]
    """Describes the token in the OpenAPI schema (Swagger UI's Authorize button)."""

    target_class = "orders.api.authentication.ClientTokenAuthentication"
    name = "clientToken"

    def get_security_definition(self, auto_schema: Any) -> dict[str, str]:
        return {
            "type": "http",
            "scheme": "bearer",
            "description": "An integration client's API token (`Token <key>` works too).",
        }
