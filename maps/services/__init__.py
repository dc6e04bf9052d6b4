"""Writes of layouts: creating maps from plain data, LIF imports, marking layout changes, zones,
saving the layout editor's versions, and releasing maps to vehicles."""

from maps.services.editor import (
    LayoutConflictError,
    LayoutPayloadError,
    check_layout_draft,
    save_layout_version,
)
from maps.services.layouts import create_layout, mark_layout_changed
from maps.services.lif_import import import_lif
from maps.services.releases import distribute_release, release_map
from maps.services.zones import (
    ZoneError,
    create_zone,
    delete_zone,
    set_zones_enabled,
    update_zone,
)

__all__ = [
    "LayoutConflictError",
    "LayoutPayloadError",
    "ZoneError",
    "check_layout_draft",
    "create_layout",
    "create_zone",
    "delete_zone",
    "distribute_release",
    "import_lif",
    "mark_layout_changed",
    "release_map",
    "save_layout_version",
    "set_zones_enabled",
    "update_zone",
]
