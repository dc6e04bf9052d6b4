"""The deployment files match the project, and the documented backup/restore brings data back."""

import re
import shutil
import subprocess
import uuid
from pathlib import Path

import pytest
import yaml
from django.conf import settings
from django.contrib.auth.models import User
from django.db import connection

from fleet.models import AuditEntry

ROOT = Path(__file__).resolve().parents[2]
DEPLOY = ROOT / "deploy"
# Variables read outside fleet/settings.py (the download links of map releases).
READ_ELSEWHERE = {"FLEET_PUBLIC_URL": ROOT / "control" / "map_store.py"}


def _procfile() -> dict[str, str]:
    lines = (ROOT / "Procfile").read_text().splitlines()
    return dict(line.split(": ", 1) for line in lines if line.strip())


def _is_read(name: str) -> bool:
    files = [ROOT / "fleet" / "settings.py"] + (
        [READ_ELSEWHERE[name]] if name in READ_ELSEWHERE else []
    )
    return any(f'"{name}"' in path.read_text() for path in files)


def test_every_example_variable_is_read_by_the_project() -> None:
    names = re.findall(r"^([A-Z_]+)=", (DEPLOY / "fleet.env.example").read_text(), re.MULTILINE)
    unread = [name for name in names if not _is_read(name)]
    assert names
    assert not unread, f"fleet.env.example sets variables nobody reads: {unread}"


def test_compose_runs_every_procfile_process_and_a_standby() -> None:
    compose = yaml.safe_load((DEPLOY / "docker-compose.yml").read_text())
    services = compose["services"]
    image_cmd = yaml.safe_load((DEPLOY / "docker" / "Dockerfile").read_text().split("CMD ")[-1])
    commands = [str(s.get("command", " ".join(image_cmd))) for s in services.values()]
    programs = {"web": "daphne", "control": "run_control", "worker": "worker", "beat": "beat"}
    for process, command in _procfile().items():
        assert programs[process] in command, (process, command)
        assert any(programs[process] in c for c in commands), f"compose does not run {process}"
    assert sum("run_control" in c for c in commands) == 2, "the standby pair is missing"
    assert {"postgres", "redis", "mosquitto", "migrate"} <= services.keys()


def test_systemd_units_cover_the_procfile_and_name_existing_commands() -> None:
    units = {p.name: p.read_text() for p in (DEPLOY / "systemd").glob("*.service")}
    execs = [re.search(r"^ExecStart=(.*)$", text, re.MULTILINE).group(1) for text in units.values()]  # type: ignore[union-attr]
    for program in ("daphne", "run_control", "worker", "beat"):
        assert any(program in e for e in execs), program
    commands = {p.stem for p in ROOT.glob("*/management/commands/*.py")}
    for e in execs:
        if "manage.py" in e:
            assert e.split("manage.py ")[1].split()[0] in commands
    target = (DEPLOY / "systemd" / "openfleet.target").read_text()
    assert all(name.replace("@.", "@1.") in target or name in target for name in units)


@pytest.mark.skipif(shutil.which("systemd-analyze") is None, reason="systemd-analyze not installed")
def test_systemd_units_verify(tmp_path: Path) -> None:
    # Paths and users of the target host do not exist here: check the unit syntax only.
    for unit in (DEPLOY / "systemd").iterdir():
        text = re.sub(
            r"^ExecStart=\S+", "ExecStart=/bin/true", unit.read_text(), flags=re.MULTILINE
        )
        text = re.sub(r"^(User|Group)=.*$", r"\1=root", text, flags=re.MULTILINE)
        (tmp_path / unit.name.replace("@.", "@1.")).write_text(text)
    result = subprocess.run(
        ["systemd-analyze", "verify", "--man=no", *map(str, sorted(tmp_path.iterdir()))],
        capture_output=True,
        text=True,
        cwd=tmp_path,
        timeout=60,
    )
    assert result.returncode == 0, result.stderr
    assert not result.stderr.strip()


@pytest.mark.django_db(transaction=True)
@pytest.mark.skipif(
    shutil.which("pg_dump") is None
    or not settings.DATABASES["default"]["ENGINE"].endswith("postgresql"),
    reason="needs PostgreSQL and its client tools",
)
def test_the_documented_backup_and_restore_bring_the_data_back(tmp_path: Path) -> None:
    """pg_dump --format=custom, pg_restore into an empty database: docs/DEPLOYMENT.md's steps."""
    User.objects.create_user("night-shift")
    AuditEntry.objects.create(actor="night-shift", action="order.create", target_id="T-1")
    db = settings.DATABASES["default"]
    base = f"postgresql://{db['USER']}@{db['HOST']}:{db['PORT']}"
    dump = tmp_path / "fleet.dump"
    subprocess.run(
        ["pg_dump", "--format=custom", f"--file={dump}", f"{base}/{db['NAME']}"],
        check=True,
        timeout=120,
    )
    restored = f"fleet_restore_{uuid.uuid4().hex[:8]}"
    with connection.cursor() as cursor:
        cursor.execute(f'CREATE DATABASE "{restored}"')
    try:
        subprocess.run(
            ["pg_restore", "--no-owner", f"--dbname={base}/{restored}", str(dump)],
            check=True,
            timeout=120,
        )
        counts = subprocess.run(
            [
                "psql",
                "-At",
                f"{base}/{restored}",
                "-c",
                "select (select count(*) from auth_user where username='night-shift'),"
                " (select count(*) from fleet_auditentry where target_id='T-1'),"
                " (select count(*) from django_migrations)",
            ],
            check=True,
            capture_output=True,
            text=True,
            timeout=60,
        ).stdout.strip()
        users, entries, migrations = (int(n) for n in counts.split("|"))
        assert (users, entries) == (1, 1)
        with connection.cursor() as cursor:
            cursor.execute("select count(*) from django_migrations")
            assert migrations == cursor.fetchone()[0]
    finally:
        with connection.cursor() as cursor:
            cursor.execute(f'DROP DATABASE IF EXISTS "{restored}" WITH (FORCE)')
