"""Production settings pass Django's deployment checklist (`check --deploy`, fail on warnings)."""

import os
import secrets
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def deploy_check(**overrides: str) -> subprocess.CompletedProcess[str]:
    env = {
        key: value
        for key, value in os.environ.items()
        if not key.startswith(("SECRET_KEY", "FLEET_", "SECURE_", "DEBUG"))
    }
    env.update(DJANGO_SETTINGS_MODULE="fleet.settings", ALLOWED_HOSTS="fleet.example.com")
    env.update(overrides)
    command = [sys.executable, "manage.py", "check", "--deploy", "--fail-level", "WARNING"]
    return subprocess.run(command, cwd=ROOT, env=env, capture_output=True, text=True, timeout=120)


def test_production_settings_pass_the_deployment_checklist(tmp_path: Path) -> None:
    key_file = tmp_path / "secret_key"
    key_file.write_text(secrets.token_urlsafe(50) + "\n")
    result = deploy_check(SECRET_KEY_FILE=str(key_file), FLEET_HTTPS="true", DEBUG="false")
    assert result.returncode == 0, result.stdout + result.stderr
    assert "no issues" in result.stdout


def test_the_checklist_catches_plain_http_and_the_development_key() -> None:
    result = deploy_check(DEBUG="false")
    assert result.returncode != 0
    for warning in ("security.W009", "security.W012", "security.W016", "security.W004"):
        assert warning in result.stderr + result.stdout
