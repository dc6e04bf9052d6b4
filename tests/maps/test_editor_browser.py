"""The layout editor in a real browser: draw a layout, save it, then vehicles drive on it.

Drives the system Chromium with Playwright (never a downloaded browser) against pytest-django's
live server. The acceptance test then starts the fleet's real processes (control, a Celery
worker, the simulator with the saved layout) like `tests/e2e` does, and a transport order on the
drawn layout must finish. Without Chromium, or without PostgreSQL, Redis and Mosquitto for the
acceptance part, the tests are skipped, unless FLEET_REQUIRE_SERVICES=1 (CI), where they fail.
"""

import os
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import pytest
from django.contrib.auth import get_user_model
from django.db import connections

from maps.demo import warehouse_layout
from maps.models import Edge, Map, MapVersion, Node, Station, Zone
from maps.selectors import validate_layout
from maps.services import create_layout, mark_layout_changed
from orders.models import TransportOrder
from orders.services import create_transport_order
from robots.models import Vehicle
from tests.browser import CHROMIUM, CHROMIUM_ARGS, in_thread, skip_or_fail
from tests.e2e.conftest import REAL, start_fleet
from tests.e2e.processes import Process, wait_until

SCREENSHOT = Path("/tmp/editor.png")
BIG_SCREENSHOT = Path("/tmp/editor-5000.png")
PROBLEM_SCREENSHOT = Path("/tmp/editor-problem.png")
USERNAME, PASSWORD = "planner", "editor-test-password"
TIMEOUT_MS = 15_000

# The layout drawn in the test: a loop of six aisle nodes 4 m apart, spurs to a pick, a drop
# and a parking station (where the simulated vehicle starts).
LOOP = [(0, 0), (4, 0), (8, 0), (8, 4), (4, 4), (0, 4)]
SPURS = {"PICK": ((4, 0), (4, -2)), "DROP": ((4, 4), (4, 6)), "PARK": ((0, 0), (-2, 0))}
SLOW_ZONE = [(6.5, -1), (9.5, -1), (9.5, 5), (6.5, 5)]

pytestmark = [pytest.mark.browser, pytest.mark.django_db(transaction=True)]


@pytest.fixture
def chromium() -> str:
    """The system Chromium, or skip (fail under FLEET_REQUIRE_SERVICES=1)."""
    if not os.path.exists(CHROMIUM):
        skip_or_fail(f"Chromium not found at {CHROMIUM} (apt-get install chromium)")
    try:
        import playwright.sync_api  # noqa: F401
    except ImportError:
        skip_or_fail("playwright is not installed")
    return CHROMIUM


@contextmanager
def editor_page(chromium: str) -> Iterator[tuple[Any, list[str]]]:
    """A browser page and its console messages. Playwright runs an asyncio loop in this thread
    while the page is open, so the ORM may only be used before and after (Django refuses it)."""
    from playwright.sync_api import sync_playwright

    with sync_playwright() as playwright:
        browser = playwright.chromium.launch(executable_path=chromium, args=CHROMIUM_ARGS)
        try:
            page = browser.new_page(viewport={"width": 1440, "height": 900})
            page.set_default_timeout(TIMEOUT_MS)
            console: list[str] = []
            page.on("console", lambda m: console.append(f"{m.type}: {m.text} {m.location['url']}"))
            page.on("pageerror", lambda e: console.append(f"pageerror: {e}"))
            page.on(
                "response",
                lambda r: r.status >= 400 and console.append(f"http: {r.status} {r.url}"),
            )
            yield page, console
        finally:
            browser.close()


@pytest.fixture
def staff_login(transactional_db: None) -> None:
    get_user_model().objects.create_superuser(USERNAME, "planner@example.com", PASSWORD)


def log_in(page: Any, base: str, next_url: str) -> None:
    page.goto(f"{base}/admin/login/?next={next_url}")
    page.fill("#id_username", USERNAME)
    page.fill("#id_password", PASSWORD)
    page.click("input[type=submit]")
    page.wait_for_url(f"{base}{next_url}")


def click_at(page: Any, x: float, y: float, *, double: bool = False) -> None:
    """Click the canvas where the layout point (x, y) m is drawn."""
    sx, sy = page.evaluate("([x, y]) => layoutEditor.toScreen(x, y)", [x, y])
    box = page.locator("#editor-canvas").bounding_box()
    page.mouse.click(box["x"] + sx, box["y"] + sy)


def count(page: Any, what: str) -> int:
    return int(page.evaluate(f"() => layoutEditor.model.{what}.size"))


def draw_small_layout(page: Any) -> None:
    """With the editor's tools, as a planner would: nodes, two-way edges, stations, a zone."""
    page.click('.tool[data-tool="node"]')
    for x, y in LOOP:
        click_at(page, x, y)
    assert count(page, "nodes") == len(LOOP)

    page.click('.tool[data-tool="edge"]')
    assert page.is_checked("#two-way")
    for x, y in [*LOOP, LOOP[0]]:
        click_at(page, x, y)  # a chain of two-way edges around the loop
    page.keyboard.press("Escape")
    for aisle, spur in SPURS.values():
        click_at(page, *aisle)
        click_at(page, *spur)  # empty space: a new node, joined both ways
        page.keyboard.press("Escape")
    assert count(page, "edges") == 2 * (len(LOOP) + len(SPURS))

    page.click('.tool[data-tool="station"]')
    for kind, (_, spur) in SPURS.items():
        page.select_option("#station-kind", kind)
        click_at(page, *spur)
    assert count(page, "stations") == len(SPURS)

    page.click('.tool[data-tool="zone"]')
    page.select_option("#zone-type", "SPEED_LIMIT")
    for x, y in SLOW_ZONE:
        click_at(page, x, y)
    page.keyboard.press("Enter")
    assert count(page, "zones") == 1
    page.fill("#properties input[type=number]", "0.8")  # the zone's speed limit
    page.press("#properties input[type=number]", "Enter")


def test_a_layout_drawn_in_the_editor_is_saved_validated_and_driven(
    live_server: Any,
    chromium: str,
    staff_login: None,
    tmp_path: Path,
    stop_all: list[Process],
) -> None:
    layout = create_layout(spec={"mapId": "hall", "name": "Hall", "nodes": [], "edges": []})
    base = live_server.url

    with editor_page(chromium) as (page, console):
        log_in(page, base, "/layouts/")
        console.clear()  # only the layout pages' own messages count (admin has no favicon)
        page.click(f'a[href="/layouts/{layout.pk}/edit/"]')
        page.wait_for_function("() => window.layoutEditor && layoutEditor.stats.draws > 0")
        draw_small_layout(page)

        page.click("#validate")
        page.wait_for_selector(".finding-empty >> text=No findings")
        page.fill("#note", "first layout of the hall")
        page.click("#save")
        page.wait_for_selector('#status[data-state="saved"]')
        assert page.inner_text("#status") == "saved as version 1"
        page.click('.tool[data-tool="select"]')
        click_at(page, 8, 0)  # select a node: the side panel shows it
        page.wait_for_selector("#properties h3 >> text=Node")
        assert page.input_value("#properties input[type=text]") == "N3"
        page.keyboard.press("f")  # fit the drawing into the view
        page.screenshot(path=str(SCREENSHOT))
        errors = [m for m in console if m.startswith(("error", "pageerror", "http"))]
        assert not errors, errors

    layout.refresh_from_db()
    assert layout.version == 1
    version = MapVersion.objects.get(map=layout)
    assert (version.saved_by.username, version.note) == (USERNAME, "first layout of the hall")
    assert Node.objects.filter(map=layout).count() == len(LOOP) + len(SPURS)
    assert Edge.objects.filter(map=layout).count() == 2 * (len(LOOP) + len(SPURS))
    positions = {(n.x, n.y) for n in Node.objects.filter(map=layout)}
    assert positions == {*LOOP, *(spur for _, spur in SPURS.values())}
    stations = {s.kind: s for s in Station.objects.filter(map=layout).select_related("node")}
    assert sorted(s.station_id for s in stations.values()) == ["DROP-1", "PARK-1", "PICK-1"]
    assert {kind: (s.node.x, s.node.y) for kind, s in stations.items()} == {
        kind: spur for kind, (_, spur) in SPURS.items()
    }
    zone = Zone.objects.get(map=layout)
    assert (zone.zone_type, zone.max_speed) == ("SPEED_LIMIT", 0.8)
    assert validate_layout(map=layout) == []

    drive_one_order(layout, stations["PICK"], stations["DROP"], tmp_path, stop_all)


def drive_one_order(
    layout: Map, pick: Station, drop: Station, tmp_path: Path, stop_all: list[Process]
) -> None:
    """Acceptance: the real processes drive a transport order on the drawn layout to the end."""
    env = fleet_environment()
    stop_all.extend(start_fleet(env, tmp_path, layout, vehicles=1))
    wait_until(lambda: Vehicle.objects.filter(connection="ONLINE").exists(), 60, "online", stop_all)

    order = create_transport_order(source=pick, destination=drop, load_id="EDITOR-1")
    wait_until(
        lambda: TransportOrder.objects.get(pk=order.pk).status == "FINISHED",
        120,
        "the order on the drawn layout finished",
        stop_all,
    )

    vehicle = Vehicle.objects.get()
    assert vehicle.last_node_id == drop.node.node_id


def fleet_environment() -> dict[str, str]:
    """The processes' environment, as tests/e2e's `fleet_env` builds it (skip without services)."""
    if any(not url.startswith(("postgres", "redis", "mqtt")) for url in REAL.values()):
        skip_or_fail(f"the acceptance part needs PostgreSQL, Redis and Mosquitto; have {REAL}")
    db = connections["default"].settings_dict
    env = {key: value for key, value in os.environ.items() if not key.startswith("PYTEST")}
    env.update(
        {
            "DJANGO_SETTINGS_MODULE": "fleet.settings",
            "DATABASE_URL": f"postgres://{db['USER']}@{db['HOST']}:{db['PORT']}/{db['NAME']}",
            "REDIS_URL": REAL["REDIS_URL"],
            "MQTT_URL": REAL["MQTT_URL"],
            "VDA5050_INTERFACE": f"editor{os.getpid()}",
            "CELERY_TASK_ALWAYS_EAGER": "0",
            "FLEET_FLUSH_INTERVAL": "0.5",
        }
    )
    return env


def test_editing_shows_problems_and_conflicts_and_saves_moves(
    live_server: Any, chromium: str, staff_login: None, demo_map: Map
) -> None:
    TransportOrder.objects.create(
        source=Station.objects.get(station_id="PICK-1"),
        destination=Station.objects.get(station_id="DROP-1"),
    )

    with editor_page(chromium) as (page, console):
        log_in(page, live_server.url, f"/layouts/{demo_map.pk}/edit/")
        console.clear()
        page.wait_for_function("() => window.layoutEditor && layoutEditor.stats.draws > 0")
        page.evaluate("() => layoutEditor.focusOn('node', 'A5.3')")
        start = page.evaluate("() => layoutEditor.toScreen(15, 9)")
        end = page.evaluate("() => layoutEditor.toScreen(16, 10)")
        box = page.locator("#editor-canvas").bounding_box()
        page.mouse.move(box["x"] + start[0], box["y"] + start[1])
        page.mouse.down()
        page.mouse.move(box["x"] + end[0], box["y"] + end[1], steps=8)
        page.mouse.up()
        page.click("#save")
        page.wait_for_selector('#status[data-state="saved"]')

        page.evaluate("() => layoutEditor.focusOn('station', 'PICK-1')")
        page.keyboard.press("Delete")
        page.click("#save")
        page.wait_for_selector('#status[data-state="error"]')
        problem = page.inner_text("#findings .finding")
        page.click("#findings .finding")  # a problem without an element path: stays put
        page.screenshot(path=str(PROBLEM_SCREENSHOT))

        in_thread(lambda: mark_layout_changed(maps=[demo_map]))  # someone else saves meanwhile
        page.evaluate("() => layoutEditor.focusOn('node', 'A0.0')")
        page.keyboard.press("Delete")
        page.click("#save")
        page.wait_for_function(
            "() => document.querySelector('#status').textContent.includes('reload')"
        )
        errors = [m for m in console if m.startswith(("error", "pageerror"))]

    assert "station PICK-1 cannot be deleted" in problem
    assert errors == [m for m in errors if "409" in m or "422" in m]  # the answers themselves
    node = Node.objects.get(map=demo_map, node_id="A5.3")
    assert (node.x, node.y) == (16.0, 10.0)
    assert Station.objects.filter(station_id="PICK-1").exists()
    assert Node.objects.filter(map=demo_map, node_id="A0.0").exists()
    assert MapVersion.objects.get(map=demo_map).number == 1


def test_the_editor_stays_quick_with_5000_nodes(
    live_server: Any, chromium: str, staff_login: None
) -> None:
    layout = create_layout(spec=warehouse_layout(columns=100, rows=50, map_id="big"))
    nodes = Node.objects.filter(map=layout).count()
    base = live_server.url

    with editor_page(chromium) as (page, console):
        log_in(page, base, "/layouts/")
        console.clear()
        started = time.perf_counter()
        page.goto(f"{base}/layouts/{layout.pk}/edit/")
        page.wait_for_function("() => window.layoutEditor && layoutEditor.stats.draws > 0")
        load_seconds = time.perf_counter() - started
        assert count(page, "nodes") == nodes > 5000

        full_redraw_ms = page.evaluate(
            """() => { const t = performance.now();
                       for (let i = 0; i < 20; i++) layoutEditor.draw();
                       return (performance.now() - t) / 20; }"""
        )
        canvas = page.locator("#editor-canvas").bounding_box()
        middle = (canvas["x"] + canvas["width"] / 2, canvas["y"] + canvas["height"] / 2)
        page.mouse.move(*middle)
        interaction_started = time.perf_counter()
        for _ in range(10):
            page.mouse.wheel(0, -120)  # zoom in at the middle
        page.mouse.down()
        page.mouse.move(middle[0] + 200, middle[1] + 120, steps=20)  # pan
        page.mouse.up()
        page.wait_for_function("() => layoutEditor.stats.draws > 5")
        interaction_seconds = time.perf_counter() - interaction_started

        x, y = page.evaluate(
            "() => { const n = layoutEditor.model.nodes.get('A50.25'); return [n.x, n.y]; }"
        )
        page.evaluate("([x, y]) => layoutEditor.focusOn('node', 'A50.25')", [x, y])
        click_at(page, x, y)
        page.wait_for_selector("#properties input[value='A50.25']")
        page.keyboard.press("f")
        page.screenshot(path=str(BIG_SCREENSHOT))
        errors = [m for m in console if m.startswith(("error", "pageerror", "http"))]

    assert not errors, errors
    assert load_seconds < 10, f"page ready after {load_seconds:.1f} s"
    assert full_redraw_ms < 150, f"a full redraw takes {full_redraw_ms:.0f} ms"
    assert interaction_seconds < 10, f"zooming and panning took {interaction_seconds:.1f} s"
