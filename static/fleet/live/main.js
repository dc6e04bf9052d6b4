// Open Fleet live page: the canvas map, the details panel and the two tables.
//
// Vehicle rows arrive over the websocket as throttled snapshots from `control`
// (`vehicles.update`: the vehicles that changed, at most 5 times a second) and are merged into
// `vehicles`; the map animates towards each new pose on its own frames, the tables follow once
// a second. Orders are fetched again as JSON when the websocket says they changed.
//
// `window.fleetMap` is a small read-mostly hook for tests and benchmarks: drawn positions,
// screen coordinates to click at, the selection, and frame/snapshot counters.

import { DetailsPanel } from "./details.js";
import { LiveMap, vehicleKey } from "./map.js";
import { VehicleTable, renderOrders, setText } from "./tables.js";

const TABLE_INTERVAL_MS = 1000;
const ORDERS_MIN_INTERVAL_MS = 1000;
const ORDERS_POLL_MS = 10000;
const RECONNECT_MIN_MS = 500;
// At most 1 s between attempts (1.25 s with jitter): a page must be live again within 5 s of
// the server (or its Redis) coming back (RELIABILITY.md §5), catch-up read included; at 30 s
// it could stay stale for half a minute, and a busy CI machine took 5.15 s with 3 s and
// 5.24 s with 2 s (the Redis-loss fault row).
const RECONNECT_MAX_MS = 1000;
const LIVE_DATA_FRESH_MS = 2000; // database rows do not overwrite live rows younger than this
const CATCH_UP_AGAIN_MS = 2000; // after a reconnect the database is read again this much later
const ROUTE_STATUSES = new Set(["driving", "busy", "paused", "error"]);

const vehicles = new Map(); // vehicle key -> latest row
const counters = { snapshots: 0, rows: 0, bytes: 0, messageMs: 0, since: performance.now() };
const socketState = { socket: null, attempts: 0, everOpened: false, timer: 0 };
const ordersState = { timer: 0, inFlight: false, again: false, lastFetch: 0 };
let map = null;
let layout = null;
let details = null;
let table = null;
let selection = null; // {kind: "vehicle", key} | {kind: "station", id} | null
let tableDirty = true;

function readJsonScript(id) {
  const element = document.getElementById(id);
  return element ? JSON.parse(element.textContent) : null;
}

// ---------------------------------------------------------------- vehicles

// Take a live update (websocket, control.snapshots.LiveDeltas): `rows` are whole vehicles
// (control leaves empty fields out, so a missing field is empty, not "as before"); `changes`
// carry only the fields that changed, null for one that became empty.
function applyVehicleUpdate(rows, changes) {
  const now = performance.now();
  for (const row of rows) {
    row.liveAt = now;
    if (row.id !== null && row.id !== undefined) {
      vehicles.delete(`${row.manufacturer}/${row.serial}`); // seen before it was registered
      if (map) map.removeVehicle(`${row.manufacturer}/${row.serial}`);
    }
    vehicles.set(vehicleKey(row), row);
    if (map) map.setVehicle(row, now);
  }
  for (const change of changes) {
    const key = vehicleKey(change);
    const row = vehicles.get(key);
    if (!row) continue; // not known yet: its whole row comes with the next keyframe
    for (const field in change) {
      if (change[field] === null) delete row[field];
      else row[field] = change[field];
      if (row.sinceOpen) row.sinceOpen.add(field);
    }
    row.liveAt = now;
    if (map) map.setVehicle(row, now);
  }
  counters.snapshots += 1;
  counters.rows += rows.length + changes.length;
  tableDirty = true;
}

// Merge a database snapshot (all vehicles, no routes, possibly a second behind live data).
function applyVehicleSnapshot(rows) {
  const now = performance.now();
  const present = new Set(rows.map(vehicleKey));
  for (const [key, known] of [...vehicles]) {
    if (!present.has(key) && !isLiveFresh(known, now)) {
      vehicles.delete(key);
      if (map) map.removeVehicle(key);
    }
  }
  for (const row of rows) {
    const key = vehicleKey(row);
    const known = vehicles.get(key);
    if (known && known.sinceOpen) {
      catchUp(known, row, now);
      continue;
    }
    if (known && isLiveFresh(known, now)) continue;
    const { base: _base, horizon: _horizon, ...fields } = row; // routes come only live
    const merged = known ? { ...known, ...fields } : { ...row };
    if (!ROUTE_STATUSES.has(merged.status)) Object.assign(merged, { base: [], horizon: [] });
    vehicles.set(key, merged);
    if (map) map.setVehicle(merged, now);
  }
  tableDirty = true;
}

// A row from before a reconnect that no whole live row replaced yet: control sends only what
// changed and counts what it sent while the socket (or Redis) was down as delivered, so its
// fields are as old as the outage except those changed since the reconnect. The database has
// the others (flushed twice a second); it knows no routes or transport orders (null there).
function catchUp(known, row, now) {
  for (const field in row) {
    if (row[field] !== null && field !== "base" && field !== "horizon" && !known.sinceOpen.has(field)) {
      known[field] = row[field];
    }
  }
  if (!ROUTE_STATUSES.has(known.status) && !known.sinceOpen.has("base")) Object.assign(known, { base: [], horizon: [] });
  if (map) map.setVehicle(known, now);
}

function isLiveFresh(row, now) {
  return Boolean(row.liveAt) && now - row.liveAt < LIVE_DATA_FRESH_MS;
}

// ---------------------------------------------------------------- selection and details

function select(next) {
  selection = next;
  if (map && map.selection !== next) {
    map.selection = next;
    map.requestDraw();
  }
  refreshDetails();
  tableDirty = true;
  refreshTable();
}

function selectVehicle(key) {
  select(selection && selection.kind === "vehicle" && selection.key === key ? null : { kind: "vehicle", key });
}

function refreshDetails() {
  if (!details) return;
  if (selection && selection.kind === "vehicle" && vehicles.has(selection.key)) {
    details.showVehicle(selection.key, vehicles.get(selection.key));
  } else if (selection && selection.kind === "station") {
    const station = layout.stations.find((s) => s.id === selection.id);
    const here = [...vehicles.values()].filter((row) => row.last_node === station.node).map((row) => row.serial);
    details.showStation(station, here);
  } else {
    details.hide();
  }
}

function refreshTable() {
  if (!tableDirty) return;
  tableDirty = false;
  const key = selection && selection.kind === "vehicle" ? selection.key : null;
  table.render(vehicles, key);
}

// ---------------------------------------------------------------- orders

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
    renderOrders((await fetchJson("/live/orders.json")).orders);
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
    applyVehicleSnapshot((await fetchJson("/live/vehicles.json")).vehicles);
  } catch (error) {
    reportFetchError(error);
  }
}

class SignedOutError extends Error {}

async function fetchJson(url) {
  const response = await fetch(url, { credentials: "same-origin", headers: { Accept: "application/json" } });
  const type = response.headers.get("content-type") || "";
  if (response.redirected || response.status === 401 || response.status === 403 || !type.includes("json")) {
    throw new SignedOutError(`${url}: not signed in`);
  }
  if (!response.ok) throw new Error(`${url}: HTTP ${response.status}`);
  return response.json();
}

function reportFetchError(error) {
  if (error instanceof SignedOutError) setConnection("signed-out", "signed out – reload to log in");
  console.warn("live page:", error.message);
}

// ---------------------------------------------------------------- websocket

function connect() {
  clearTimeout(socketState.timer);
  const text = socketState.everOpened ? "reconnecting" : "connecting";
  setConnection(text, text);
  const scheme = window.location.protocol === "https:" ? "wss" : "ws";
  const socket = new WebSocket(`${scheme}://${window.location.host}/ws/live/`);
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
    // Events were missed while the socket was down: catch up from the database (`catchUp`),
    // now and once more when sends that failed just after the outage would have come.
    for (const row of vehicles.values()) row.sinceOpen = new Set();
    refreshVehicles();
    setTimeout(refreshVehicles, CATCH_UP_AGAIN_MS);
    scheduleOrdersRefresh();
  }
}

function onSocketMessage(event) {
  const started = performance.now();
  try {
    handleMessage(event.data);
  } finally {
    counters.messageMs += performance.now() - started;
  }
}

function handleMessage(data) {
  let message;
  try {
    message = JSON.parse(data);
  } catch {
    return;
  }
  counters.bytes += data.length;
  const payload = message.payload || {};
  if (message.event === "vehicles.update") {
    applyVehicleUpdate(payload.vehicles || [], payload.changes || []);
  } else if (message.event === "orders.changed") {
    scheduleOrdersRefresh();
  }
}

function onSocketClose(event) {
  if (socketState.socket !== event.target) return;
  socketState.socket = null;
  if (event.code === 4401 || event.code === 4403) {
    setConnection("signed-out", event.code === 4401 ? "signed out – reload to log in" : "no permission");
    return;
  }
  // Backoff with jitter: 0.5 s, then every 1 s.
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

// ---------------------------------------------------------------- the hook for tests and benchmarks

function exposeHook() {
  const screenOf = (x, y) => {
    const box = map.canvas.getBoundingClientRect();
    const p = map.toScreen(x, y);
    return { x: box.left + p.x, y: box.top + p.y };
  };
  window.fleetMap = {
    vehicleCount: () => vehicles.size,
    // Where the vehicle is drawn now (layout metres, radians), or null.
    vehiclePosition(key) {
      const sprite = map.sprites.get(String(key));
      return sprite && sprite.pose ? { ...sprite.pose } : null;
    },
    // Client (page) coordinates of a vehicle's drawn centre or a station, to click at.
    vehicleScreenPosition(key) {
      const sprite = map.sprites.get(String(key));
      return sprite && sprite.pose ? screenOf(sprite.pose.x, sprite.pose.y) : null;
    },
    stationScreenPosition(id) {
      const station = layout.stations.find((s) => s.id === id);
      return station ? screenOf(station.x, station.y) : null;
    },
    selection: () => (selection ? { ...selection } : null),
    camera: () => ({ ...map.camera }),
    stats: () => ({
      frames: map.stats.frames,
      drawMs: map.stats.drawMs,
      snapshots: counters.snapshots,
      rows: counters.rows,
      bytes: counters.bytes,
      messageMs: counters.messageMs,
      seconds: (performance.now() - counters.since) / 1000,
    }),
    resetStats() {
      Object.assign(map.stats, { frames: 0, drawMs: 0 });
      Object.assign(counters, { snapshots: 0, rows: 0, bytes: 0, messageMs: 0, since: performance.now() });
    },
  };
}

// ---------------------------------------------------------------- start

function bindZoomButtons() {
  const actions = { "zoom-in": () => map.zoom(1.4), "zoom-out": () => map.zoom(1 / 1.4), "zoom-fit": () => map.fit() };
  for (const button of document.querySelectorAll("[data-map-action]")) {
    button.addEventListener("click", () => actions[button.dataset.mapAction]?.());
  }
}

function start() {
  layout = readJsonScript("layout-data");
  table = new VehicleTable({ onSelect: selectVehicle });
  const canvas = document.getElementById("map");
  if (layout && canvas) {
    map = new LiveMap(canvas, layout, { onSelect: (picked) => select(picked) });
    details = new DetailsPanel({ onClose: () => select(null) });
    bindZoomButtons();
    exposeHook();
  }
  applyVehicleSnapshot(readJsonScript("vehicles-data") || []);
  renderOrders(readJsonScript("orders-data") || []);
  refreshTable();
  connect();
  setInterval(() => {
    refreshTable();
    if (selection) refreshDetails();
  }, TABLE_INTERVAL_MS);
  setInterval(refreshOrders, ORDERS_POLL_MS);
}

if (document.readyState === "loading") {
  document.addEventListener("DOMContentLoaded", start);
} else {
  start();
}
