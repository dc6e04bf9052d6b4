"""Releasing maps as files for vehicles, and distributing a release (REFERENCE K.47).

A release freezes the map's layout as a LIF 1.0 file with its checksum; distributing it tells
`control` (through the command queue) to bring every vehicle that supports map distribution
onto that version: downloadMap, then enableMap, then deleteMap of older versions
(`control.map_sync`).
"""

import hashlib
import json
import secrets
from typing import Any

from django.db import transaction
from django.db.models import Max
from django.utils import timezone

from fleet import audit
from fleet.control_queue import send_command
from fleet.exceptions import InvalidRequestError
from maps.models import Map, MapRelease
from maps.selectors.layout import export_map_lif

MAX_NOTE = 500


@transaction.atomic
def release_map(
    *, map: Map, user: Any = None, note: str = "", distribute: bool = False
) -> MapRelease:
    """Freeze `map`'s current layout as the next release (version "r<n>"); optionally distribute.

    The file is the map's LIF export with sorted keys and the layout's last change as its
    export timestamp, so the same layout gives the same checksum. A map without nodes cannot
    be released (a vehicle could not drive on it).
    """
    if len(note) > MAX_NOTE:
        raise InvalidRequestError(f"note is longer than {MAX_NOTE} characters")
    locked = Map.objects.select_for_update().get(pk=map.pk)
    if not locked.nodes.exists():
        raise InvalidRequestError(f"map {locked.map_id} has no nodes to release")
    document = export_map_lif(map=locked)
    # The layout's last change, not "now": the same layout gives the same file and checksum.
    document["metaInformation"]["exportTimestamp"] = locked.updated_at.strftime(
        "%Y-%m-%dT%H:%M:%S.%fZ"
    )
    content = json.dumps(document, sort_keys=True, indent=1).encode()
    number = (locked.releases.aggregate(n=Max("number"))["n"] or 0) + 1
    release = MapRelease.objects.create(
        map=locked,
        number=number,
        version=f"r{number}",
        content=content,
        checksum=hashlib.sha256(content).hexdigest(),
        size=len(content),
        revision=locked.revision,
        token=secrets.token_urlsafe(24),
        note=note,
        created_by=_user(user),
    )
    audit.record(
        "map.release",
        target_type="map",
        target_id=locked.map_id,
        detail={"version": release.version, "sha256": release.checksum},
    )
    if distribute:
        distribute_release(release=release, user=user)
    return release


@transaction.atomic
def distribute_release(*, release: MapRelease, user: Any = None) -> MapRelease:
    """Make `release` the version its map's vehicles must have enabled, and wake `control`.

    Distributing an older release again rolls the vehicles back to it (it becomes the latest
    distributed one). `control` also re-reads the targets every few seconds, so a lost wake-up
    only delays the downloads.
    """
    release.distributed_at = timezone.now()
    release.distributed_by = _user(user)
    release.save(update_fields=["distributed_at", "distributed_by"])
    map_id, version = release.map.map_id, release.version
    audit.record("map.distribute", target_type="map", target_id=map_id, detail={"version": version})
    transaction.on_commit(lambda: send_command("maps.distribute", map_id=map_id, version=version))
    return release


def _user(user: Any) -> Any:
    return user if getattr(user, "is_authenticated", False) else None
