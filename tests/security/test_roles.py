"""The role groups, the commands that set them up and assign them, and the scopes of clients."""

import importlib
from types import SimpleNamespace
from typing import Any

import pytest
from django.apps import apps
from django.contrib.auth import get_user_model
from django.contrib.auth.models import Group, Permission
from django.core.management import call_command
from django.test import Client

from fleet import roles
from orders import services
from orders.models import IntegrationClient
from tests.factories import user_with_role

pytestmark = pytest.mark.django_db


def test_every_fleet_capability_is_a_real_permission() -> None:
    for name in (
        roles.VIEW_OPERATIONS,
        roles.OPERATE_ORDERS,
        roles.COMMAND_VEHICLES,
        roles.SEND_TO_CHARGE_OR_PARK,
        roles.ACKNOWLEDGE_ALERTS,
        roles.MAINTAIN_VEHICLES,
        roles.VIEW_REPORTS,
        roles.VIEW_AUDIT,
        roles.MANAGE_LAYOUTS,
        roles.ADMINISTER,
    ):
        app_label, codename = name.split(".")
        assert Permission.objects.filter(
            content_type__app_label=app_label, codename=codename
        ).exists(), name


def test_sync_roles_is_idempotent_and_repairs_a_changed_group() -> None:
    first = roles.sync_roles()
    operator = Group.objects.get(name=roles.OPERATOR)
    operator.permissions.add(Permission.objects.get(codename="manage_layouts"))
    Group.objects.get(name=roles.MANAGER).delete()

    second = roles.sync_roles()

    assert first == second
    assert Group.objects.filter(name__in=roles.ROLES).count() == len(roles.ROLES)
    assert not operator.permissions.filter(codename="manage_layouts").exists()
    assert second[roles.ADMINISTRATOR] == Permission.objects.count()


def test_each_role_holds_its_capabilities_and_no_other(django_user_model: Any) -> None:
    every = {f"fleet.{codename}" for codename, _ in roles.FLEET_CAPABILITIES} | {roles.VIEW_AUDIT}
    for role in roles.ROLES:
        user = user_with_role(role)
        held = {name for name in every if user.has_perm(name)}
        assert held == set(roles.ROLE_PERMISSIONS[role]), role


def test_setup_roles_and_create_user_commands(capsys: pytest.CaptureFixture[str]) -> None:
    Group.objects.filter(name__in=roles.ROLES).delete()

    call_command("setup_roles")
    call_command("create_user", "lena", "--role", "operator", "--password", "pw-lena-123")
    call_command("create_user", "lena", "--role", "technician")  # changes the role

    lena = get_user_model().objects.get(username="lena")
    assert [g.name for g in lena.groups.all()] == [roles.TECHNICIAN]
    assert lena.is_staff  # technicians use the admin
    assert lena.check_password("pw-lena-123")
    assert "operator:" in capsys.readouterr().out


def test_an_administrator_sets_a_clients_scopes_in_the_admin() -> None:
    client = Client()
    client.force_login(user_with_role(roles.ADMINISTRATOR))

    response = client.post(
        "/admin/orders/integrationclient/add/",
        {
            "name": "wms",
            "description": "",
            "is_active": "on",
            "scopes": ["orders:read", "loads:write"],
            "tokens-TOTAL_FORMS": "0",
            "tokens-INITIAL_FORMS": "0",
        },
    )

    assert response.status_code == 302, response.content.decode()[:2000]
    assert IntegrationClient.objects.get(name="wms").scopes == ["orders:read", "loads:write"]
    page = client.get("/admin/orders/integrationclient/").content.decode()
    assert "orders:read, loads:write" in page


def test_unknown_scopes_are_refused() -> None:
    with pytest.raises(Exception, match="unknown scopes: orders:everything"):
        services.create_integration_client(name="x", scopes=["orders:everything"])


def test_clients_that_existed_before_scopes_get_every_scope() -> None:
    migration = importlib.import_module("orders.migrations.0008_integration_client_scopes")
    old = services.create_integration_client(name="old-erp")
    assert old.scopes == []  # new clients start without scopes

    migration.grant_existing_clients_every_scope(
        apps, SimpleNamespace(connection=SimpleNamespace(alias="default"))
    )

    old.refresh_from_db()
    assert old.scopes == list(roles.ALL_API_SCOPES)
