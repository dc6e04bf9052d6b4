"""Fixtures of the security tests: one signed-in user per role (plus nobody and a user without
a role), nothing leaves for control or webhooks, and a tally of the checked combinations."""

from typing import Any

import pytest

from fleet import roles
from tests.factories import user_with_role

NOBODY = "anonymous"
NO_ROLE = "no role"
PRINCIPALS = (NOBODY, NO_ROLE, *roles.ROLES)

# kind of matrix → combinations checked in this run (printed at the end of the run)
CHECKED: dict[str, int] = {}


def count(kind: str, combinations: int) -> None:
    CHECKED[kind] = CHECKED.get(kind, 0) + combinations


def pytest_terminal_summary(terminalreporter: Any) -> None:
    if CHECKED:
        terminalreporter.section("security matrix")
        for kind, combinations in sorted(CHECKED.items()):
            terminalreporter.write_line(f"{kind}: {combinations} combinations checked")
        terminalreporter.write_line(f"total: {sum(CHECKED.values())}")


@pytest.fixture(autouse=True)
def nothing_leaves(monkeypatch: pytest.MonkeyPatch) -> list[tuple[str, dict[str, Any]]]:
    """Commands for control are kept here instead of going to Redis; no webhook is posted."""
    sent: list[tuple[str, dict[str, Any]]] = []
    for module in ("transport", "dispatch", "vehicles"):
        monkeypatch.setattr(
            f"orders.services.{module}.send_command",
            lambda kind, **payload: sent.append((kind, payload)),
        )
    monkeypatch.setattr(
        "orders.services.webhooks._post", lambda *a: pytest.fail("no webhook may leave the test")
    )
    return sent


@pytest.fixture
def principals(db: None) -> dict[str, Any]:
    """Principal name → user (None: not signed in)."""
    users: dict[str, Any] = {NOBODY: None, NO_ROLE: user_with_no_role()}
    for role in roles.ROLES:
        users[role] = user_with_role(role)
    return users


def user_with_no_role() -> Any:
    from django.contrib.auth import get_user_model

    return get_user_model().objects.create_user("no-role-user")
