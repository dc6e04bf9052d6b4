"""The admin lists alerts, rules and the inventory's models (staff work there)."""

import pytest

from alerts.services import raise_alert
from inventory.services import register_load

pytestmark = pytest.mark.django_db


@pytest.mark.parametrize(
    "url",
    [
        "/admin/alerts/alert/",
        "/admin/alerts/escalationrule/",
        "/admin/alerts/escalationrule/add/",
        "/admin/inventory/loadcarrier/",
        "/admin/inventory/storagelocation/",
        "/admin/inventory/movement/",
        "/admin/inventory/discrepancy/",
    ],
)
def test_admin_pages_answer(admin_client, url) -> None:
    raise_alert(cause="x:1", message="something")
    register_load(load_id="L1")

    assert admin_client.get(url).status_code == 200


def test_alerts_are_read_only_in_the_admin(admin_client) -> None:
    alert = raise_alert(cause="x:1", message="something")

    assert admin_client.get("/admin/alerts/alert/add/").status_code == 403
    page = admin_client.get(f"/admin/alerts/alert/{alert.pk}/change/")
    assert page.status_code == 200
    assert b'name="message"' not in page.content
