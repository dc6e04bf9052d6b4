"""Reads of released map files: the current release per map and a release by its token."""

from django.db.models import QuerySet

from maps.models import Map, MapRelease


def list_releases(*, map: Map | None = None) -> QuerySet[MapRelease]:
    """Releases, newest first (of one map, or of all)."""
    releases = MapRelease.objects.select_related("map").defer("content")
    return releases if map is None else releases.filter(map=map)


def current_releases() -> dict[str, MapRelease]:
    """Per mapId the release its vehicles must have enabled: the latest distributed one."""
    current: dict[str, MapRelease] = {}
    rows = (
        MapRelease.objects.filter(distributed_at__isnull=False)
        .select_related("map")
        .defer("content")
        .order_by("map_id", "-distributed_at", "-number")
    )
    for release in rows:
        current.setdefault(release.map.map_id, release)
    return current


def release_by_token(*, token: str) -> MapRelease | None:
    """The release behind a download URL, or None."""
    return MapRelease.objects.select_related("map").filter(token=token).first()
