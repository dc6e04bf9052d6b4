"""Permission checks of the pages: one decorator for every view that needs a role's permission.

`require_permission(VIEW_OPERATIONS, to_change=OPERATE_ORDERS)` lets signed-in users holding the
first permission read the page (GET, HEAD) and those also holding `to_change` post to it. A
visitor who is not signed in goes to the login page (JSON endpoints answer 403 in JSON instead,
as their callers are scripts, not people); a signed-in user without the permission gets 403.
The permissions are named in `fleet.roles`; docs/SECURITY.md has the table of every page.
"""

from collections.abc import Callable
from functools import wraps
from typing import Any, TypeVar

from django.contrib.auth.views import redirect_to_login
from django.core.exceptions import PermissionDenied
from django.http import HttpRequest, HttpResponse, JsonResponse

View = TypeVar("View", bound=Callable[..., Any])

SAFE_METHODS = frozenset({"GET", "HEAD", "OPTIONS"})


def require_permission(
    permission: str, *, to_change: str | None = None, json: bool = False
) -> Callable[[View], View]:
    """Decorate a view: `permission` to use it at all, `to_change` as well for other methods
    than GET/HEAD/OPTIONS. `json=True` answers refusals as JSON (401 not signed in, 403)."""

    def decorate(view: View) -> View:
        @wraps(view)
        def checked(request: HttpRequest, *args: Any, **kwargs: Any) -> HttpResponse:
            user = request.user
            if not (user.is_authenticated and user.is_active):
                if json:
                    return JsonResponse({"detail": "sign in first"}, status=401)
                return redirect_to_login(request.get_full_path())
            needed = [permission]
            if to_change is not None and request.method not in SAFE_METHODS:
                needed.append(to_change)
            if not user.has_perms(needed):
                if json:
                    return JsonResponse({"detail": "your role may not do this"}, status=403)
                raise PermissionDenied
            response: HttpResponse = view(request, *args, **kwargs)
            return response

        checked.required_permissions = (permission, to_change)  # type: ignore[attr-defined]
        return checked  # type: ignore[return-value]

    return decorate
