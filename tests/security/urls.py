"""Walk the URL resolver: every route of the site with its name and parameters, so the matrix
tests cover pages that are added later without anyone listing them by hand."""

from collections.abc import Iterator
from dataclasses import dataclass
from typing import Any

from django.urls import URLPattern, URLResolver, get_resolver, reverse


@dataclass(frozen=True)
class Route:
    name: str  # "namespace:name", or "" when the route has none
    route: str  # the pattern as written, for messages
    parameters: tuple[str, ...]
    view: Any


def walk(patterns: Any = None, prefix: str = "", namespace: str = "") -> Iterator[Route]:
    """Every URL pattern under `patterns` (the whole site by default)."""
    for pattern in get_resolver().url_patterns if patterns is None else patterns:
        if isinstance(pattern, URLResolver):
            inner = namespace
            if pattern.namespace:
                inner = f"{namespace}:{pattern.namespace}" if namespace else pattern.namespace
            yield from _walk_resolver(pattern, prefix, inner)
        elif isinstance(pattern, URLPattern):
            name = pattern.name or ""
            if name and namespace:
                name = f"{namespace}:{name}"
            yield Route(
                name=name,
                route=prefix + str(pattern.pattern),
                parameters=tuple(pattern.pattern.regex.groupindex),
                view=pattern.callback,
            )


def _walk_resolver(resolver: URLResolver, prefix: str, namespace: str) -> Iterator[Route]:
    outer = tuple(resolver.pattern.regex.groupindex)
    for route in walk(resolver.url_patterns, prefix + str(resolver.pattern), namespace):
        yield Route(route.name, route.route, outer + route.parameters, route.view)


# A value for each URL parameter: ids that do not exist (the permission check comes first, so
# an allowed user gets 404, a refused one 403), and valid words where the pattern lists them.
SAMPLE_ARGUMENTS: dict[str, Any] = {
    "pk": 999999,
    "action": "acknowledge",
    "kind": "stock",
    "name": "throughput",
    "token": "no-such-token",
    "manufacturer": "sim",
    "serial": "NO-SUCH-VEHICLE",
    "uidb64": "MQ",
    "load_id": "NO-SUCH-LOAD",
}


def sample_url(route: Route, **overrides: Any) -> str:
    """The route's URL with sample parameters (overrides win)."""
    arguments = {name: SAMPLE_ARGUMENTS.get(name, "x") for name in route.parameters}
    arguments.update(overrides)
    return reverse(route.name, kwargs=arguments)
