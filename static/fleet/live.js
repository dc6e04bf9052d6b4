// Open Fleet live page.
//
// Draws the layout as SVG once, then keeps vehicles, routes and the two tables current:
// vehicle rows arrive over the websocket (`vehicles.update`, changed vehicles only) and are
// merged into `state.vehicles`; one requestAnimationFrame loop moves the existing SVG elements
// towards their latest pose. Orders are re-fetched as JSON when the websocket says they changed.
//
// Coordinates: the layout is in metres with y pointing up; SVG's y points down, so every point
// is drawn at (x, -y) and headings are negated.

(() => {
  "use strict";

  const SVG_NS = "http://www.w3.org/2000/svg";
  const MAP_MARGIN = 2.5; // metres of space around the layout
  const SNAP_DISTANCE = 8; // metres: larger jumps are not animated
  const MIN_TWEEN_MS = 80;
  const MAX_TWEEN_MS = 1000;
  const TWEEN_STRETCH = 1.15; // tweens last a bit longer than the gap between updates
  const ORDERS_MIN_INTERVAL_MS = 1000;
  const ORDERS_POLL_MS = 10000;
  const RECONNECT_MIN_MS = 1000;
  const RECONNECT_MAX_MS = 30000;
  const LIVE_DATA_FRESH_MS = 2000; // snapshot rows do not overwrite live rows younger than this
  const ROUTE_STATUSES = new Set(["driving", "busy", "paused", "error"]);
  const OPEN_ORDER_STATUSES = new Set(["NEW", "ASSIGNED", "IN_PROGRESS"]);
  const VEHICLE_SHAPE = "-0.45,-0.35 0.25,-0.35 0.55,0 0.25,0.35 -0.45,0.35";

  const state = {
    layout: null,
    vehicles: new Map(), // id -> latest row
    sprites: new Map(), // id -> SVG elements and animation of one vehicle
    tableRows: new Map(), // id -> <tr> of the vehicles table
    dirtyRows: new Set(), // vehicle ids whose table row needs redrawing
    selected: null, // id of the highlighted vehicle
    frame: 0,
    layers: null,
  };

  const socketState = { socket: null, attempts: 0, everOpened: false, timer: 0 };
  const ordersState = { timer: 0, inFlight: false, again: false, lastFetch: 0 };

  // ---------------------------------------------------------------- small helpers

  function readJsonScript(id) {
    const element = document.getElementById(id);
    return element ? JSON.parse(element.textContent) : null;
  }

  function svg(tag, attributes = {}, parent = null) {
    const element = document.createElementNS(SVG_NS, tag);
    for (const [name, value] of Object.entries(attributes)) {
      element.setAttribute(name, String(value));
    }
    if (parent) parent.appendChild(element);
    return element;
  }

  function html(tag, className = "", text = "") {
    const element = document.createElement(tag);
    if (className) element.className = className;
    if (text) element.textContent = text;
    return element;
  }

  function fmt(value) {
    return value.toFixed(3);
  }

  function points(list) {
    return list.map(([x, y]) => `${fmt(x)},${fmt(-y)}`).join(" ");
  }

  function hasPosition(row) {
    return Number.isFinite(row.x) && Number.isFinite(row.y);
  }

  function onThisMap(row) {
    return !row.map || !state.layout || row.map === state.layout.mapId;
  }

  function setText(element, text) {
    const value = text === null || text === undefined || text === "" ? "–" : String(text);
    if (element.textContent !== value) element.textContent = value;
  }

  function shortestTurn(from, to) {
    const turn = (to - from) % (2 * Math.PI);
    if (turn > Math.PI) return turn - 2 * Math.PI;
    if (turn < -Math.PI) return turn + 2 * Math.PI;
    return turn;
  }

  // ---------------------------------------------------------------- layout

  function layoutBounds(layout) {
    const xs = layout.nodes.map((node) => node.x);
    const ys = layout.nodes.map((node) => node.y);
    if (!xs.length) return { minX: -5, minY: -5, maxX: 5, maxY: 5 };
    return {
      minX: Math.min(...xs), maxX: Math.max(...xs),
      minY: Math.min(...ys), maxY: Math.max(...ys),
    };
  }

  function viewBoxFor(layout) {
    const b = layoutBounds(layout);
    const width = b.maxX - b.minX + 2 * MAP_MARGIN;
    const height = b.maxY - b.minY + 2 * MAP_MARGIN;
    // Flipped y: the top edge of the view is the largest layout y.
    return [b.minX - MAP_MARGIN, -(b.maxY + MAP_MARGIN), width, height].map(fmt).join(" ");
  }

  function drawLayout(root, layout) {
    root.setAttribute("viewBox", viewBoxFor(layout));
    const layers = {
      zones: svg("g", { class: "zones" }, root),
      edges: svg("g", { class: "edges" }, root),
      stations: svg("g", { class: "stations" }, root),
      nodes: svg("g", { class: "nodes" }, root),
      routes: svg("g", { class: "routes" }, root),
      vehicles: svg("g", { class: "vehicles" }, root),
    };
    drawArrowMarker(root);
    drawZones(layers.zones, layout);
    drawEdges(layers.edges, layout);
    drawStations(layers.stations, layout);
    drawNodes(layers.nodes, layout);
    return layers;
  }

  // Enabled zones under the aisles, tinted by type; the tooltip names the zone and its rule.
  function drawZones(layer, layout) {
    for (const zone of layout.zones || []) {
      const polygon = svg("polygon", {
        class: `zone zone-${zone.type.toLowerCase().replace(/_/g, "-")}`,
        points: zone.vertices.map(([x, y]) => `${fmt(x)},${fmt(-y)}`).join(" "),
        "data-zone": zone.id,
      }, layer);
      const rule = zone.maxSpeed ? ` · ${zone.maxSpeed} m/s` : "";
      svg("title", {}, polygon).textContent = `${zone.name} (${zone.type.toLowerCase()}${rule})`;
    }
  }

  function drawArrowMarker(root) {
    const defs = svg("defs", {}, root);
    const marker = svg("marker", {
      id: "oneway", viewBox: "0 0 10 10", refX: 10, refY: 5,
      markerWidth: 6, markerHeight: 6, orient: "auto-start-reverse",
    }, defs);
    svg("path", { d: "M0,0 L10,5 L0,10 z", class: "oneway-arrow" }, marker);
  }

  function drawEdges(layer, layout) {
    const byId = new Map(layout.nodes.map((node) => [node.id, node]));
    const directed = new Set(layout.edges.map((edge) => `${edge.start}>${edge.end}`));
    const drawn = new Set();
    for (const edge of layout.edges) {
      const start = byId.get(edge.start);
      const end = byId.get(edge.end);
      if (!start || !end) continue;
      const pair = [edge.start, edge.end].sort().join("|");
      if (drawn.has(pair)) continue; // a two-way aisle is two edges: draw one line
      drawn.add(pair);
      const twoWay = directed.has(`${edge.end}>${edge.start}`);
      const line = svg("line", {
        class: twoWay ? "edge" : "edge oneway",
        x1: fmt(start.x), y1: fmt(-start.y), x2: fmt(end.x), y2: fmt(-end.y),
        "data-edge": edge.id,
      }, layer);
      if (!twoWay) line.setAttribute("marker-end", "url(#oneway)");
    }
  }

  function drawNodes(layer, layout) {
    for (const node of layout.nodes) {
      const dot = svg("circle", {
        class: "node", cx: fmt(node.x), cy: fmt(-node.y), r: 0.12, "data-node": node.id,
      }, layer);
      svg("title", {}, dot).textContent = node.id;
    }
  }

  function drawStations(layer, layout) {
    const size = 0.9;
    for (const station of layout.stations) {
      const group = svg("g", {
        class: `station kind-${station.kind}`, "data-station": station.id,
        transform: `translate(${fmt(station.x)} ${fmt(-station.y)})`,
      }, layer);
      svg("rect", {
        class: "station-box", x: -size / 2, y: -size / 2, width: size, height: size, rx: 0.1,
      }, group);
      const label = svg("text", { class: "station-label", y: size / 2 + 0.55 }, group);
      label.textContent = station.name || station.id;
      const kind = station.kind.toLowerCase();
      svg("title", {}, group).textContent = `${station.name || station.id} (${kind}) at ${station.node}`;
    }
  }

  // ---------------------------------------------------------------- vehicles on the map

  function createSprite(row) {
    const group = svg("g", { class: "vehicle", "data-id": row.id }, state.layers.vehicles);
    const ring = svg("circle", { class: "vehicle-ring", r: 0.95 }, group);
    const body = svg("g", { class: "vehicle-body" }, group);
    svg("polygon", { class: "vehicle-shape", points: VEHICLE_SHAPE }, body);
    const load = svg("rect", { class: "vehicle-load", x: -0.3, y: -0.18, width: 0.36, height: 0.36 }, body);
    const label = svg("text", { class: "vehicle-label", y: -0.75 }, group);
    const title = svg("title", {}, group);
    const base = svg("polyline", { class: "route-base", "data-id": row.id }, state.layers.routes);
    const horizon = svg("polyline", { class: "route-horizon", "data-id": row.id }, state.layers.routes);
    // Traffic management: nodes reserved beyond the base (light dots), and a line to the
    // vehicle this one waits for at its decision point.
    const reserved = svg("g", { class: "reserved", "data-id": row.id }, state.layers.routes);
    const wait = svg("line", { class: "wait-link", "data-id": row.id }, state.layers.routes);
    group.addEventListener("click", () => selectVehicle(row.id));
    return {
      group, ring, body, load, label, title, base, horizon, reserved, wait, waitsFor: null,
      route: { base: [], horizon: [] },
      pose: null, from: null, to: null, t0: 0, duration: 0, lastUpdate: 0, interval: 0,
    };
  }

  function removeSprite(id) {
    const sprite = state.sprites.get(id);
    if (!sprite) return;
    sprite.group.remove();
    sprite.base.remove();
    sprite.horizon.remove();
    sprite.reserved.remove();
    sprite.wait.remove();
    state.sprites.delete(id);
  }

  function updateSprite(sprite, row, now) {
    const selected = row.id === state.selected ? " selected" : "";
    sprite.group.setAttribute("class", `vehicle status-${row.status}${selected}`);
    sprite.load.style.display = row.loaded ? "" : "none";
    setText(sprite.label, row.serial);
    const errors = row.errors && row.errors.length ? ` · ${row.errors.join(", ")}` : "";
    setText(sprite.title, `${row.serial} · ${row.status}${errors}`);

    const visible = hasPosition(row) && onThisMap(row);
    sprite.group.style.display = visible ? "" : "none";
    sprite.group.dataset.x = visible ? fmt(row.x) : "";
    sprite.group.dataset.y = visible ? fmt(row.y) : "";
    if (!visible) {
      hideSprite(sprite);
      return;
    }
    sprite.route = { base: row.base || [], horizon: row.horizon || [] };
    drawReserved(sprite, row.reserved || []);
    sprite.waitsFor = (row.waiting_for || [])[0] || null;
    const theta = Number.isFinite(row.theta) ? row.theta : (sprite.to ? sprite.to.theta : 0);
    setTarget(sprite, { x: row.x, y: row.y, theta }, now);
  }

  // No position or another map: no shape, no route, and no tween from the old place later.
  function hideSprite(sprite) {
    Object.assign(sprite, { pose: null, from: null, to: null, route: { base: [], horizon: [] } });
    sprite.base.setAttribute("points", "");
    sprite.horizon.setAttribute("points", "");
    drawReserved(sprite, []);
    sprite.waitsFor = null;
    sprite.wait.style.display = "none";
  }

  function drawReserved(sprite, nodes) {
    const key = JSON.stringify(nodes);
    if (sprite.reserved.dataset.key === key) return;
    sprite.reserved.dataset.key = key;
    sprite.reserved.textContent = "";
    for (const [x, y] of nodes) {
      svg("circle", { class: "reserved-node", cx: fmt(x), cy: fmt(-y), r: 0.45 }, sprite.reserved);
    }
  }

  // A waiting vehicle points at the one it waits for (both drawn where they are now).
  function drawWait(sprite, pose) {
    const other = sprite.waitsFor ? spriteBySerial(sprite.waitsFor) : null;
    if (!other || !other.pose) {
      sprite.wait.style.display = "none";
      return;
    }
    sprite.wait.style.display = "";
    sprite.wait.setAttribute("x1", fmt(pose.x));
    sprite.wait.setAttribute("y1", fmt(-pose.y));
    sprite.wait.setAttribute("x2", fmt(other.pose.x));
    sprite.wait.setAttribute("y2", fmt(-other.pose.y));
  }

  function spriteBySerial(serial) {
    for (const [id, row] of state.vehicles) {
      if (row.serial === serial) return state.sprites.get(id) || null;
    }
    return null;
  }

  // Start a tween from where the vehicle is drawn now to `target`, lasting about as long as
  // the gap between the last two updates, so that motion stays continuous at ~5 updates/s.
  // A smoothed gap, stretched a little, avoids stops when an update arrives late.
  function setTarget(sprite, target, now) {
    const gap = sprite.lastUpdate ? Math.min(MAX_TWEEN_MS, now - sprite.lastUpdate) : 0;
    sprite.lastUpdate = now;
    sprite.interval = sprite.interval ? 0.7 * sprite.interval + 0.3 * gap : gap;
    const from = sprite.pose;
    const jump = from ? Math.hypot(target.x - from.x, target.y - from.y) : Infinity;
    sprite.from = from;
    sprite.to = target;
    sprite.t0 = now;
    sprite.duration = jump > SNAP_DISTANCE ? 0
      : Math.min(MAX_TWEEN_MS, Math.max(MIN_TWEEN_MS, sprite.interval * TWEEN_STRETCH));
  }

  // Move one sprite to its pose at time `now`; true while it is still moving.
  function animateSprite(sprite, now) {
    if (!sprite.to) return false;
    const tweening = sprite.duration > 0 && sprite.from;
    const progress = tweening ? Math.min(1, (now - sprite.t0) / sprite.duration) : 1;
    const pose = progress >= 1 ? sprite.to : interpolate(sprite.from, sprite.to, progress);
    sprite.pose = pose;
    sprite.group.setAttribute("transform", `translate(${fmt(pose.x)} ${fmt(-pose.y)})`);
    sprite.body.setAttribute("transform", `rotate(${(-pose.theta * 180 / Math.PI).toFixed(1)})`);
    drawRoute(sprite, pose);
    return progress < 1;
  }

  function interpolate(from, to, t) {
    return {
      x: from.x + (to.x - from.x) * t,
      y: from.y + (to.y - from.y) * t,
      theta: from.theta + shortestTurn(from.theta, to.theta) * t,
    };
  }

  // The remaining route starts at the vehicle; the horizon continues where the base ends.
  function drawRoute(sprite, pose) {
    const { base, horizon } = sprite.route;
    const basePoints = base.length ? [[pose.x, pose.y], ...base] : [];
    const horizonStart = basePoints.length ? basePoints[basePoints.length - 1] : [pose.x, pose.y];
    const horizonPoints = horizon.length ? [horizonStart, ...horizon] : [];
    sprite.base.setAttribute("points", points(basePoints));
    sprite.horizon.setAttribute("points", points(horizonPoints));
    drawWait(sprite, pose);
  }

  function requestFrame() {
    if (!state.frame) state.frame = requestAnimationFrame(renderFrame);
  }

  function renderFrame(now) {
    state.frame = 0;
    let moving = false;
    for (const sprite of state.sprites.values()) {
      moving = animateSprite(sprite, now) || moving;
    }
    renderDirtyVehicleRows();
    if (moving) requestFrame();
  }

  // ---------------------------------------------------------------- vehicle state

  // Merge live rows (from the websocket) into the state: only the given vehicles change.
  function applyVehicleRows(rows) {
    const now = performance.now();
    for (const row of rows) {
      const merged = { ...(state.vehicles.get(row.id) || {}), ...row, liveAt: now };
      state.vehicles.set(row.id, merged);
      showVehicle(merged, now);
    }
    requestFrame();
  }

  // Merge a database snapshot (all vehicles, no routes, possibly a second behind live data).
  function applyVehicleSnapshot(rows) {
    const now = performance.now();
    const present = new Set(rows.map((row) => row.id));
    for (const [id, known] of [...state.vehicles]) {
      if (!present.has(id) && !isLiveFresh(known, now)) forgetVehicle(id);
    }
    for (const row of rows) {
      const known = state.vehicles.get(row.id);
      if (known && isLiveFresh(known, now)) continue;
      const { base: _base, horizon: _horizon, ...fields } = row; // routes come only live
      const merged = known ? { ...known, ...fields } : { ...row };
      if (!ROUTE_STATUSES.has(merged.status)) Object.assign(merged, { base: [], horizon: [] });
      state.vehicles.set(row.id, merged);
      showVehicle(merged, now);
    }
    requestFrame();
  }

  function isLiveFresh(row, now) {
    return Boolean(row.liveAt) && now - row.liveAt < LIVE_DATA_FRESH_MS;
  }

  function showVehicle(row, now) {
    if (state.layers) {
      let sprite = state.sprites.get(row.id);
      if (!sprite) {
        sprite = createSprite(row);
        state.sprites.set(row.id, sprite);
      }
      updateSprite(sprite, row, now);
    }
    state.dirtyRows.add(row.id);
  }

  function forgetVehicle(id) {
    state.vehicles.delete(id);
    removeSprite(id);
    const tr = state.tableRows.get(id);
    if (tr) tr.remove();
    state.tableRows.delete(id);
    updateVehicleCount();
  }

  function selectVehicle(id) {
    state.selected = state.selected === id ? null : id;
    for (const [vehicleId, sprite] of state.sprites) {
      sprite.group.classList.toggle("selected", vehicleId === state.selected);
      sprite.base.classList.toggle("selected", vehicleId === state.selected);
      sprite.horizon.classList.toggle("selected", vehicleId === state.selected);
    }
    for (const [vehicleId, tr] of state.tableRows) {
      tr.classList.toggle("selected", vehicleId === state.selected);
    }
  }

  // ---------------------------------------------------------------- vehicles table

  const VEHICLE_COLUMNS = ["serial", "status", "battery", "mode", "last_node", "order", "waits", "errors"];

  function vehicleTableBody() {
    return document.querySelector("#vehicles-table tbody");
  }

  function createVehicleRow(id) {
    const tr = html("tr");
    tr.dataset.id = id;
    for (const column of VEHICLE_COLUMNS) {
      const td = html("td", `col-${column}`);
      tr.appendChild(td);
    }
    tr.addEventListener("click", () => selectVehicle(id));
    return tr;
  }

  function renderDirtyVehicleRows() {
    if (!state.dirtyRows.size) return;
    const body = vehicleTableBody();
    for (const id of state.dirtyRows) {
      const row = state.vehicles.get(id);
      if (!row) continue;
      let tr = state.tableRows.get(id);
      if (!tr) {
        tr = createVehicleRow(id);
        state.tableRows.set(id, tr);
        insertSorted(body, tr, row.serial);
      }
      fillVehicleRow(tr, row);
    }
    state.dirtyRows.clear();
    updateVehicleCount();
  }

  function insertSorted(body, tr, serial) {
    tr.dataset.serial = serial || "";
    const later = (other) => other.dataset.serial.localeCompare(serial || "", undefined, { numeric: true }) > 0;
    const after = [...body.children].find(later);
    body.insertBefore(tr, after || null);
  }

  function fillVehicleRow(tr, row) {
    const cells = tr.children;
    setText(cells[0], row.serial);
    const mode = row.mode ? `mode ${String(row.mode).toLowerCase()}` : "";
    cells[0].title = [`${row.manufacturer || ""} ${row.serial || ""}`.trim(), mode].filter(Boolean).join(" · ");
    fillBadge(cells[1], row.status, `status-${row.status}`);
    fillBattery(cells[2], row.battery);
    setText(cells[3], row.mode ? String(row.mode).toLowerCase() : "");
    setText(cells[4], row.last_node);
    setText(cells[5], row.transport_order ? `TO-${row.transport_order}` : row.order);
    setText(cells[6], (row.waiting_for || []).join(", "));
    const errors = row.errors || [];
    setText(cells[7], errors.join(", "));
    cells[7].title = errors.join("\n");
    cells[7].classList.toggle("has-errors", errors.length > 0);
    tr.classList.toggle("offline", row.status === "offline");
  }

  function fillBadge(cell, text, className) {
    let badge = cell.firstElementChild;
    if (!badge) badge = cell.appendChild(html("span"));
    badge.className = `badge ${className}`;
    setText(badge, text ? String(text).replace("_", " ").toLowerCase() : "");
  }

  function fillBattery(cell, battery) {
    if (!Number.isFinite(battery)) {
      setText(cell, "");
      return;
    }
    if (!cell.querySelector(".battery")) {
      cell.textContent = "";
      const gauge = cell.appendChild(html("span", "battery"));
      gauge.appendChild(html("span", "battery-fill"));
      cell.appendChild(html("span", "battery-value"));
    }
    const percent = Math.max(0, Math.min(100, battery));
    const fill = cell.querySelector(".battery-fill");
    fill.style.width = `${percent.toFixed(0)}%`;
    cell.querySelector(".battery").classList.toggle("low", percent < 20);
    setText(cell.querySelector(".battery-value"), `${percent.toFixed(0)}%`);
  }

  function updateVehicleCount() {
    setText(document.getElementById("vehicles-count"), String(state.vehicles.size));
    document.getElementById("vehicles-empty").hidden = state.vehicles.size > 0;
  }

  // ---------------------------------------------------------------- orders table

  function renderOrders(orders) {
    const body = document.querySelector("#orders-table tbody");
    const rows = orders.map(orderRow);
    body.replaceChildren(...rows);
    const open = orders.filter((order) => OPEN_ORDER_STATUSES.has(order.status)).length;
    setText(document.getElementById("orders-count"), String(open));
    document.getElementById("orders-empty").hidden = orders.length > 0;
  }

  function orderRow(order) {
    const tr = html("tr");
    tr.dataset.id = order.id;
    tr.appendChild(html("td", "col-id", `TO-${order.id}`));
    const status = tr.appendChild(html("td", "col-status"));
    fillBadge(status, order.status, `order-${order.status}`);
    const path = tr.appendChild(html("td", "col-path"));
    path.append(html("span", "", order.source), html("span", "arrow", " → "));
    path.append(html("span", "", order.destination));
    tr.appendChild(html("td", "col-vehicle", order.vehicle || "–"));
    const reason = tr.appendChild(html("td", "col-reason", order.failure_reason || ""));
    reason.title = order.failure_reason || "";
    tr.title = orderTimes(order);
    return tr;
  }

  function orderTimes(order) {
    const time = (iso) => (iso ? new Date(iso).toLocaleString() : "");
    const created = `created ${time(order.created_at)}`;
    return order.finished_at ? `${created}, finished ${time(order.finished_at)}` : created;
  }

  // At most one orders fetch per second, however many `orders.changed` events arrive.
  function scheduleOrdersRefresh() {
    if (ordersState.timer) return;
    const wait = Math.max(0, ordersState.lastFetch + ORDERS_MIN_INTERVAL_MS - Date.now());
    ordersState.timer = setTimeout(() => {
      ordersState.timer = 0;
      refreshOrders();
    }, wait);
  }

  async function refreshOrders() {
    if (ordersState.inFlight) {
      ordersState.again = true;
      return;
    }
    ordersState.inFlight = true;
    ordersState.lastFetch = Date.now();
    try {
      const data = await fetchJson("/live/orders.json");
      renderOrders(data.orders);
    } catch (error) {
      reportFetchError(error);
    } finally {
      ordersState.inFlight = false;
      if (ordersState.again) {
        ordersState.again = false;
        scheduleOrdersRefresh();
      }
    }
  }

  async function refreshVehicles() {
    try {
      const data = await fetchJson("/live/vehicles.json");
      applyVehicleSnapshot(data.vehicles);
    } catch (error) {
      reportFetchError(error);
    }
  }

  class SignedOutError extends Error {}

  async function fetchJson(url) {
    const response = await fetch(url, {
      credentials: "same-origin",
      headers: { Accept: "application/json" },
    });
    const type = response.headers.get("content-type") || "";
    if (response.redirected || response.status === 401 || response.status === 403 || !type.includes("json")) {
      throw new SignedOutError(`${url}: not signed in`);
    }
    if (!response.ok) throw new Error(`${url}: HTTP ${response.status}`);
    return response.json();
  }

  function reportFetchError(error) {
    if (error instanceof SignedOutError) {
      setConnection("signed-out", "signed out – reload to log in");
    }
    console.warn("live page:", error.message);
  }

  // ---------------------------------------------------------------- websocket

  function socketUrl() {
    const scheme = window.location.protocol === "https:" ? "wss" : "ws";
    return `${scheme}://${window.location.host}/ws/live/`;
  }

  function connect() {
    clearTimeout(socketState.timer);
    setConnection(socketState.everOpened ? "reconnecting" : "connecting",
      socketState.everOpened ? "reconnecting" : "connecting");
    const socket = new WebSocket(socketUrl());
    socketState.socket = socket;
    socket.addEventListener("open", onSocketOpen);
    socket.addEventListener("message", onSocketMessage);
    socket.addEventListener("close", onSocketClose);
  }

  function onSocketOpen() {
    const reconnected = socketState.everOpened;
    socketState.everOpened = true;
    socketState.attempts = 0;
    setConnection("live", "live");
    if (reconnected) {
      // Events were missed while the socket was down: catch up from the database.
      refreshVehicles();
      scheduleOrdersRefresh();
    }
  }

  function onSocketMessage(event) {
    let message;
    try {
      message = JSON.parse(event.data);
    } catch {
      return;
    }
    handleEvent(message.event, message.payload || {});
  }

  function handleEvent(name, payload) {
    if (name === "vehicles.update") {
      applyVehicleRows(payload.vehicles || []);
    } else if (name === "orders.changed") {
      scheduleOrdersRefresh();
    }
  }

  function onSocketClose(event) {
    if (socketState.socket !== event.target) return;
    socketState.socket = null;
    if (event.code === 4401) {
      setConnection("signed-out", "signed out – reload to log in");
      return;
    }
    scheduleReconnect();
  }

  // Exponential backoff with jitter: 1 s, 2 s, 4 s … up to 30 s.
  function scheduleReconnect() {
    const delay = Math.min(RECONNECT_MAX_MS, RECONNECT_MIN_MS * 2 ** socketState.attempts);
    const jittered = delay * (0.75 + Math.random() * 0.5);
    socketState.attempts += 1;
    setConnection("reconnecting", `reconnecting in ${Math.round(jittered / 1000)} s`);
    socketState.timer = setTimeout(connect, jittered);
  }

  function setConnection(name, text) {
    const indicator = document.getElementById("connection");
    if (!indicator) return;
    indicator.dataset.state = name;
    setText(indicator.querySelector(".conn-text"), text);
  }

  // ---------------------------------------------------------------- start

  function start() {
    state.layout = readJsonScript("layout-data");
    const root = document.getElementById("map");
    if (state.layout && root) state.layers = drawLayout(root, state.layout);
    applyVehicleSnapshot(readJsonScript("vehicles-data") || []);
    renderOrders(readJsonScript("orders-data") || []);
    updateVehicleCount();
    connect();
    setInterval(refreshOrders, ORDERS_POLL_MS);
  }

  if (document.readyState === "loading") {
    document.addEventListener("DOMContentLoaded", start);
  } else {
    start();
  }
})();
