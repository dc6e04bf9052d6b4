"""Writes of layouts: creating maps from plain data, LIF imports, marking layout changes."""

from maps.services.layouts import create_layout, mark_layout_changed
from maps.services.lif_import import import_lif

__all__ = ["create_layout", "import_lif", "mark_layout_changed"]
