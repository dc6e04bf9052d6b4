"""The compiled parts of the planner, when they are built and current.

`make venv` (`build_native.py`) compiles them with Cython: the hold as a C struct and
re-timing (`traffic/_holds.pyx`), and the SIPP search loop (`traffic/_search.pyx`). Each has a
plain-Python twin that gives the same results (`traffic.reservations.PyHold`,
`traffic.timing.propagate_plain`, `traffic.sipp_loop.run`); `tests/traffic/test_speedups.py`
compares them. `FLEET_TRAFFIC_PURE=1` forces the plain-Python twins.
"""

from __future__ import annotations

import importlib
import logging
import os
import pathlib
from types import SimpleNamespace

logger = logging.getLogger(__name__)
SOURCES = {"_holds": ("_holds.pyx", "_holds.pxd"), "_search": ("_search.pyx", "_holds.pxd")}


def _load() -> SimpleNamespace | None:
    """`Hold`, `propagate` and `run` compiled, or None (not built, stale, or not wanted)."""
    if os.environ.get("FLEET_TRAFFIC_PURE", "") not in ("", "0"):
        return None
    here = pathlib.Path(__file__).parent
    modules = {}
    for name, sources in SOURCES.items():
        try:
            module = importlib.import_module(f"traffic.{name}")
        except ImportError:
            logger.info("traffic: compiled planner not built (make venv): plain Python")
            return None
        built = pathlib.Path(module.__file__ or "").stat().st_mtime
        if any((here / s).exists() and (here / s).stat().st_mtime > built for s in sources):
            logger.warning("traffic: %s changed since it was built; run `make native`", name)
            return None
        modules[name] = module
    holds, search = modules["_holds"], modules["_search"]
    return SimpleNamespace(Hold=holds.Hold, propagate=holds.propagate, run=search.run)


COMPILED = _load()
