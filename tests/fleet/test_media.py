"""Uploaded files are served to staff with the right permission only, from MEDIA_ROOT only."""

from pathlib import Path

import pytest
from django.contrib.auth.models import User
from django.core.files.base import ContentFile
from django.core.files.storage import default_storage
from django.test import Client


@pytest.fixture
def stored_file(settings, tmp_path: Path) -> str:
    settings.MEDIA_ROOT = tmp_path / "media"
    (tmp_path / "secret.txt").write_text("outside the media root")
    return default_storage.save("maintenance/2026/11/photo.txt", ContentFile(b"wheel photo"))


@pytest.mark.django_db
def test_a_logged_out_visitor_is_sent_to_the_login(client: Client, stored_file: str) -> None:
    response = client.get(f"/media/{stored_file}")
    assert response.status_code == 302
    assert "/accounts/login/" in response["Location"]


@pytest.mark.django_db
def test_a_user_without_the_operations_permission_is_refused(
    client: Client, stored_file: str
) -> None:
    client.force_login(User.objects.create_user("visitor"))
    assert client.get(f"/media/{stored_file}").status_code == 403


@pytest.mark.django_db
def test_permitted_staff_get_the_file(client: Client, stored_file: str) -> None:
    client.force_login(User.objects.create_superuser("admin"))
    response = client.get(f"/media/{stored_file}")
    assert response.status_code == 200
    assert b"".join(response.streaming_content) == b"wheel photo"  # type: ignore[attr-defined]
    assert response["X-Content-Type-Options"] == "nosniff"


@pytest.mark.django_db
@pytest.mark.parametrize("name", ["../secret.txt", "missing.txt", "maintenance/../../secret.txt"])
def test_nothing_outside_media_root_or_missing_is_served(
    client: Client, stored_file: str, name: str
) -> None:
    client.force_login(User.objects.create_superuser("admin"))
    assert client.get(f"/media/{name}").status_code == 404
