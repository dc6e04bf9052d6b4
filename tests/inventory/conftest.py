"""The alerts tests' harness fixtures, shared."""

from tests.alerts.conftest import clock, make_harness

__all__ = ["clock", "make_harness"]
