// Open Fleet vehicle page: the VDA 5050 visualizer for one vehicle, live.
//
// The server renders the database snapshot; the websocket (`/ws/vehicles/<pk>/`) then brings
// the raw messages `control` saw or sent (`vehicle.messages`: new messages, and on joining the
// latest message of every topic). Every panel is derived from those messages: the header and
// state summary from the latest state and visualization, the order graph from the latest order
// and the state's remaining nodes and edges, the log from all of them. The page renews its
// watch every few seconds; `control` stops streaming when no page does.
//
// Coordinates: metres with y up; SVG y points down, so points are drawn at (x, -y).

(() => {
  "use strict";

  const SVG_NS = "http://www.w3.org/2000/svg";
  const MAP_MARGIN = 2;
  const LOG_LIMIT = 500; // messages kept in the page
  const LOG_SHOWN = 200; // rows drawn after filtering
  const WATCH_RENEW_MS = 10000; // control's watch lasts 30 s
  const SNAP_METRES = 1.0; // a click this close to a node names it as lastNodeId
  const RECONNECT_MAX_MS = 30000;
  const VEHICLE_SHAPE = "-0.45,-0.35 0.25,-0.35 0.55,0 0.25,0.35 -0.45,0.35";

  const page = {
    snapshot: {},
    layout: null,
    allowed: new Set(),
    commandUrl: "",
    socketPath: "",
    latest: new Map(), // topic -> entry
    log: [], // entries, oldest first
    seen: new Set(), // seq numbers already taken
    row: null, // control's live row of the vehicle
    selectedTopic: null,
    selectedSeq: null,
    layers: null,
    pick: null, // {x, y} chosen for initPosition
    order: null, // the current order merged over its updates: {orderId, seq, nodes, edges}
    dirty: false,
  };
  const socketState = { socket: null, attempts: 0, renew: 0, retry: 0 };

  // ---------------------------------------------------------------- helpers

  function readJsonScript(id) {
    const element = document.getElementById(id);
    return element ? JSON.parse(element.textContent) : null;
  }

  function $(id) {
    return document.getElementById(id);
  }

  function svg(tag, attributes = {}, parent = null) {
    const element = document.createElementNS(SVG_NS, tag);
    for (const [name, value] of Object.entries(attributes)) element.setAttribute(name, String(value));
    if (parent) parent.appendChild(element);
    return element;
  }

  function cell(row, text, className = "") {
    const td = document.createElement("td");
    if (className) td.className = className;
    td.textContent = text === null || text === undefined || text === "" ? "–" : String(text);
    row.appendChild(td);
    return td;
  }

  function setText(id, text) {
    const element = $(id);
    const value = text === null || text === undefined || text === "" ? "–" : String(text);
    if (element && element.textContent !== value) element.textContent = value;
  }

  function num(value, digits = 2) {
    return Number.isFinite(value) ? value.toFixed(digits) : "–";
  }

  function clock(at) {
    const date = new Date(at * 1000);
    const pad = (n, w = 2) => String(n).padStart(w, "0");
    return `${pad(date.getHours())}:${pad(date.getMinutes())}:${pad(date.getSeconds())}.` +
      pad(date.getMilliseconds(), 3);
  }

  function yesNo(value) {
    return value ? "yes" : "no";
  }

  function data(topic) {
    const entry = page.latest.get(topic);
    return entry ? entry.data : null;
  }

  // ---------------------------------------------------------------- messages

  function take(entry) {
    if (page.seen.has(entry.seq)) return false;
    page.seen.add(entry.seq);
    try {
      entry.data = JSON.parse(entry.json);
    } catch (error) {
      entry.data = null; // shown raw; control logged why it dropped it
    }
    const known = page.latest.get(entry.topic);
    if (!known || known.seq < entry.seq) page.latest.set(entry.topic, entry);
    page.log.push(entry);
    return true;
  }

  // An order update repeats only its stitching node: merge the updates of one order by
  // sequenceId (a newer message wins) so the whole order can be drawn.
  function mergeOrder(entry) {
    const order = entry.data;
    if (!order || !Array.isArray(order.nodes)) return;
    if (!page.order || page.order.orderId !== order.orderId) {
      if (page.order && entry.seq < page.order.seq) return; // an older order arrived late
      page.order = { orderId: order.orderId, seq: entry.seq, nodes: new Map(), edges: new Map() };
    }
    page.order.seq = Math.max(page.order.seq, entry.seq);
    for (const [list, into] of [[order.nodes, page.order.nodes], [order.edges || [], page.order.edges]]) {
      for (const item of list) {
        const known = into.get(item.sequenceId);
        if (!known || known.seq <= entry.seq) into.set(item.sequenceId, { seq: entry.seq, item });
      }
    }
  }

  function onMessages(payload) {
    let changed = false;
    const fresh = [...Object.values(payload.latest || {}), ...(payload.messages || [])]
      .filter(take);
    fresh.sort((a, b) => a.seq - b.seq);
    for (const entry of fresh) {
      if (entry.topic === "order" && entry.direction === "out") mergeOrder(entry);
    }
    changed = fresh.length > 0;
    if (payload.vehicle) {
      page.row = payload.vehicle;
      changed = true;
    }
    if (!changed) return;
    page.log.sort((a, b) => a.seq - b.seq);
    if (page.log.length > LOG_LIMIT) page.log.splice(0, page.log.length - LOG_LIMIT);
    if (page.seen.size > 4 * LOG_LIMIT) page.seen = new Set(page.log.map((e) => e.seq));
    scheduleRender();
  }

  function scheduleRender() {
    if (page.dirty) return;
    page.dirty = true;
    requestAnimationFrame(() => {
      page.dirty = false;
      renderAll();
    });
  }

  function renderAll() {
    renderHeader();
    renderSummary();
    renderChips();
    renderGraph();
    renderLog();
    renderTracks();
  }

  // ---------------------------------------------------------------- header and summary

  function pose() {
    const state = data("state");
    const vis = page.latest.get("visualization");
    const st = page.latest.get("state");
    const fromVis = vis && vis.data && vis.data.agvPosition;
    const fromState = state && state.agvPosition;
    if (fromVis && (!fromState || vis.seq > st.seq)) return fromVis;
    if (fromState) return fromState;
    const s = page.snapshot;
    return Number.isFinite(s.x) ? { x: s.x, y: s.y, theta: s.theta, mapId: s.map } : null;
  }

  function velocity() {
    const vis = page.latest.get("visualization");
    const st = page.latest.get("state");
    const candidates = [vis, st].filter((e) => e && e.data && e.data.velocity);
    candidates.sort((a, b) => b.seq - a.seq);
    return candidates.length ? candidates[0].data.velocity : null;
  }

  function lastIncoming() {
    let last = null;
    for (const entry of page.latest.values()) {
      if (entry.direction === "in" && (!last || entry.at > last.at)) last = entry;
    }
    return last;
  }

  function connectionText() {
    if (page.row && page.row.connection) return page.row.connection;
    const connection = data("connection");
    if (connection && connection.connectionState) return connection.connectionState;
    return page.snapshot.connection;
  }

  function renderHeader() {
    const state = data("state");
    const position = pose();
    setText("h-map", (position && position.mapId) || page.snapshot.map);
    setText("h-mode", state ? state.operatingMode : page.snapshot.mode);
    setText("h-position", position
      ? `x ${num(position.x)} m, y ${num(position.y)} m, θ ${num(position.theta)} rad` +
        (position.positionInitialized === false ? " (not initialised)" : "")
      : "");
    const v = velocity();
    setText("h-velocity", v ? `vx ${num(v.vx)}, vy ${num(v.vy)} m/s, ω ${num(v.omega)} rad/s` : "");
    const badge = document.createElement("span");
    const connection = connectionText();
    badge.className = `badge conn-${String(connection).toLowerCase()}`;
    badge.textContent = connection;
    $("h-connection").replaceChildren(badge);
    const last = lastIncoming();
    setText("h-updated", last ? `${clock(last.at)} (${last.topic})` : page.snapshot.last_seen);
  }

  function renderSummary() {
    const state = data("state");
    if (!state) return; // the server-rendered snapshot stays
    setText("s-order", state.orderId);
    setText("s-update", state.orderUpdateId);
    setText("s-last-node", state.lastNodeId);
    setText("s-sequence", state.lastNodeSequenceId);
    setText("s-driving", yesNo(state.driving));
    setText("s-paused", yesNo(state.paused));
    const battery = state.batteryState || {};
    setText("s-battery", Number.isFinite(battery.batteryCharge)
      ? `${battery.batteryCharge.toFixed(0)} %${battery.charging ? " (charging)" : ""}` : "");
    const loads = state.loads;
    setText("s-loads", loads === undefined || loads === null ? "unknown"
      : loads.length ? loads.map((l) => l.loadId || l.loadType || "load").join(", ") : "none");

    const actions = [...(state.actionStates || []), ...(state.instantActionStates || [])];
    const body = $("actions-table").tBodies[0];
    body.replaceChildren(...actions.slice(-30).map((action) => {
      const tr = document.createElement("tr");
      tr.dataset.status = action.actionStatus || "";
      cell(tr, action.actionType);
      cell(tr, action.actionId, "mono");
      cell(tr, action.actionStatus, `status-${action.actionStatus}`);
      cell(tr, action.resultDescription || action.actionDescription);
      return tr;
    }));
    const errors = state.errors || [];
    $("errors-list").replaceChildren(...(errors.length ? errors : [null]).map((error) => {
      const li = document.createElement("li");
      if (!error) {
        li.className = "none";
        li.textContent = "none";
      } else {
        li.className = `level-${error.errorLevel}`;
        li.textContent = `${error.errorLevel} ${error.errorType}` +
          (error.errorDescription ? `: ${error.errorDescription}` : "");
      }
      return li;
    }));
  }

  // ---------------------------------------------------------------- chips and JSON

  function renderChips() {
    for (const chip of document.querySelectorAll(".chip")) {
      const entry = page.latest.get(chip.dataset.topic);
      chip.classList.toggle("has-data", Boolean(entry));
      chip.setAttribute("aria-pressed", String(chip.dataset.topic === page.selectedTopic));
      chip.querySelector(".chip-time").textContent = entry ? clock(entry.at) : "–";
    }
    if (page.selectedTopic) showJson($("json-view"), page.latest.get(page.selectedTopic));
  }

  function showJson(element, entry) {
    if (!entry) {
      element.textContent = "nothing received since control started";
      return;
    }
    const text = entry.data ? JSON.stringify(entry.data, null, 2) : entry.json;
    const note = entry.note ? `// dropped by control: ${entry.note}\n` : "";
    if (element === $("json-view")) {
      $("json-title").textContent = `${entry.topic} · ${clock(entry.at)}` +
        (entry.truncated ? " · truncated" : "");
    }
    if (element.textContent !== note + text) element.textContent = note + text;
  }

  // ---------------------------------------------------------------- map and order graph

  function drawLayout(root, layout) {
    const xs = layout.nodes.map((n) => n.x);
    const ys = layout.nodes.map((n) => n.y);
    const [minX, maxX] = xs.length ? [Math.min(...xs), Math.max(...xs)] : [-5, 5];
    const [minY, maxY] = ys.length ? [Math.min(...ys), Math.max(...ys)] : [-5, 5];
    root.setAttribute("viewBox", [minX - MAP_MARGIN, -(maxY + MAP_MARGIN),
      maxX - minX + 2 * MAP_MARGIN, maxY - minY + 2 * MAP_MARGIN].join(" "));
    const layers = {
      layout: svg("g", { class: "layout" }, root),
      order: svg("g", { class: "order" }, root),
      vehicle: svg("g", { class: "vehicle-layer" }, root),
      pick: svg("g", { class: "pick-layer" }, root),
    };
    const byId = new Map(layout.nodes.map((n) => [n.id, n]));
    for (const edge of layout.edges) {
      const a = byId.get(edge.start);
      const b = byId.get(edge.end);
      if (a && b) svg("line", { class: "l-edge", x1: a.x, y1: -a.y, x2: b.x, y2: -b.y }, layers.layout);
    }
    for (const station of layout.stations || []) {
      svg("rect", { class: `l-station kind-${station.kind}`, x: station.x - 0.35, y: -station.y - 0.35,
        width: 0.7, height: 0.7 }, layers.layout);
    }
    for (const node of layout.nodes) {
      svg("title", {}, svg("circle", { class: "l-node", cx: node.x, cy: -node.y, r: 0.12 },
        layers.layout)).textContent = node.id;
    }
    return layers;
  }

  function nodePlace(node) {
    const position = node.nodePosition;
    if (position && Number.isFinite(position.x)) return position;
    const known = page.layout && page.layout.nodes.find((n) => n.id === node.nodeId);
    return known || null;
  }

  // The order as sent, coloured by what the vehicle's state says remains: a node or edge of
  // the same order that the state no longer lists has been traversed.
  function orderGraph() {
    const order = data("order");
    const state = data("state");
    const sameOrder = order && state && state.orderId === order.orderId;
    if (order) {
      const merged = page.order && page.order.orderId === order.orderId ? page.order : null;
      const nodes = merged ? [...merged.nodes.values()].map((v) => v.item) : order.nodes || [];
      const edges = merged ? [...merged.edges.values()].map((v) => v.item) : order.edges || [];
      const nodesLeft = new Set((sameOrder ? state.nodeStates || [] : []).map((n) => n.sequenceId));
      const edgesLeft = new Set((sameOrder ? state.edgeStates || [] : []).map((e) => e.sequenceId));
      return {
        nodes: nodes.map((n) => ({ ...n, done: sameOrder && !nodesLeft.has(n.sequenceId) })),
        edges: edges.map((e) => ({ ...e, done: sameOrder && !edgesLeft.has(e.sequenceId) })),
      };
    }
    if (state && state.orderId) { // adopted or sent before the page opened: what remains
      return { nodes: state.nodeStates || [], edges: state.edgeStates || [] };
    }
    return { nodes: [], edges: [] };
  }

  function renderGraph() {
    if (!page.layers) return;
    const graph = orderGraph();
    const bySeq = new Map(graph.nodes.map((n) => [n.sequenceId, n]));
    const byId = new Map(graph.nodes.map((n) => [n.nodeId, n]));
    const layer = page.layers.order;
    layer.replaceChildren();
    for (const edge of graph.edges) {
      const a = bySeq.get(edge.sequenceId - 1) || byId.get(edge.startNodeId);
      const b = bySeq.get(edge.sequenceId + 1) || byId.get(edge.endNodeId);
      const pa = a && nodePlace(a);
      const pb = b && nodePlace(b);
      if (!pa || !pb) continue;
      const kind = edge.released === false ? "horizon" : "base";
      svg("title", {}, svg("line", {
        class: `o-edge ${kind}${edge.done ? " done" : ""}`, "data-edge": edge.edgeId,
        x1: pa.x, y1: -pa.y, x2: pb.x, y2: -pb.y,
      }, layer)).textContent = `${edge.edgeId} (#${edge.sequenceId}, ${kind})`;
    }
    for (const node of graph.nodes) {
      const place = nodePlace(node);
      if (!place) continue;
      const kind = node.released === false ? "horizon" : "base";
      svg("title", {}, svg("circle", {
        class: `o-node ${kind}${node.done ? " done" : ""}`, "data-node": node.nodeId,
        cx: place.x, cy: -place.y, r: 0.28,
      }, layer)).textContent = `${node.nodeId} (#${node.sequenceId}, ${kind})`;
    }
    const position = pose();
    const vehicleLayer = page.layers.vehicle;
    vehicleLayer.replaceChildren();
    if (position && Number.isFinite(position.x)) {
      const degrees = -((position.theta || 0) * 180) / Math.PI;
      svg("polygon", {
        class: `v-shape status-${page.row ? page.row.status : "offline"}`, points: VEHICLE_SHAPE,
        transform: `translate(${position.x} ${-position.y}) rotate(${degrees})`,
      }, vehicleLayer);
    }
  }

  function renderPick() {
    const layer = page.layers && page.layers.pick;
    if (!layer) return;
    layer.replaceChildren();
    if (!page.pick) return;
    const heading = (Number($("init-heading").value) || 0) * Math.PI / 180;
    svg("polygon", {
      class: "pick-shape", points: VEHICLE_SHAPE,
      transform: `translate(${page.pick.x} ${-page.pick.y}) rotate(${-(heading * 180) / Math.PI})`,
    }, layer);
  }

  function onMapClick(event) {
    if ($("init-form").hidden) return;
    const root = $("vmap");
    const point = root.createSVGPoint();
    point.x = event.clientX;
    point.y = event.clientY;
    const at = point.matrixTransform(root.getScreenCTM().inverse());
    let x = at.x;
    let y = -at.y;
    let nearest = null;
    for (const node of page.layout.nodes) {
      const d = Math.hypot(node.x - x, node.y - y);
      if (d <= SNAP_METRES && (!nearest || d < nearest.d)) nearest = { d, node };
    }
    if (nearest) ({ x, y } = nearest.node);
    $("init-x").value = x.toFixed(2);
    $("init-y").value = y.toFixed(2);
    $("init-node").value = nearest ? nearest.node.id : "";
    page.pick = { x, y };
    renderPick();
  }

  // ---------------------------------------------------------------- log

  function summary(entry) {
    const d = entry.data;
    if (!d) return entry.note || "not JSON";
    switch (entry.topic) {
      case "state":
        return `order ${d.orderId || "–"}/${d.orderUpdateId ?? "–"} · node ${d.lastNodeId || "–"}` +
          ` · ${d.driving ? "driving" : "standing"}${d.paused ? " · paused" : ""}` +
          ` · ${(d.errors || []).length} errors`;
      case "visualization":
        return d.agvPosition ? `x ${num(d.agvPosition.x)} y ${num(d.agvPosition.y)}` : "no position";
      case "connection":
        return d.connectionState || "";
      case "factsheet":
        return (d.typeSpecification && d.typeSpecification.seriesName) || "factsheet";
      case "order":
        return `${d.orderId}/${d.orderUpdateId} · ${(d.nodes || []).length} nodes`;
      case "instantActions":
        return (d.actions || d.instantActions || []).map((a) => a.actionType).join(", ");
      default:
        return "";
    }
  }

  function filtered() {
    const direction = $("filter-direction").value;
    const topic = $("filter-topic").value;
    const text = $("filter-text").value.trim().toLowerCase();
    const rows = [];
    for (let i = page.log.length - 1; i >= 0 && rows.length < LOG_SHOWN; i -= 1) {
      const entry = page.log[i];
      if (direction && entry.direction !== direction) continue;
      if (topic && entry.topic !== topic) continue;
      if (text && !entry.json.toLowerCase().includes(text)) continue;
      rows.push(entry);
    }
    return rows;
  }

  function renderLog(force = false) {
    if ($("filter-pause").checked && !force) return;
    setText("log-count", page.log.length);
    $("log-table").tBodies[0].replaceChildren(...filtered().map((entry) => {
      const tr = document.createElement("tr");
      tr.dataset.seq = entry.seq;
      tr.dataset.topic = entry.topic;
      tr.className = `dir-${entry.direction}${entry.seq === page.selectedSeq ? " selected" : ""}`;
      cell(tr, clock(entry.at), "mono");
      cell(tr, entry.direction === "in" ? "vehicle → master" : "master → vehicle");
      cell(tr, entry.topic);
      cell(tr, entry.data ? entry.data.headerId : "");
      cell(tr, summary(entry));
      return tr;
    }));
  }

  function onLogClick(event) {
    const tr = event.target.closest("tr[data-seq]");
    if (!tr) return;
    page.selectedSeq = Number(tr.dataset.seq);
    const entry = page.log.find((e) => e.seq === page.selectedSeq);
    $("log-json").hidden = !entry;
    if (entry) showJson($("log-json"), entry);
    renderLog(true);
  }

  function renderTracks() {
    const tracks = (page.row && page.row.instant_actions) || [];
    if (!tracks.length) return; // the server-rendered recent commands stay
    $("tracks-table").tBodies[0].replaceChildren(...tracks.slice().reverse().map((track) => {
      const tr = document.createElement("tr");
      cell(tr, "live");
      cell(tr, track.type);
      cell(tr, track.status, `status-${track.status}`);
      cell(tr, track.reason);
      return tr;
    }));
  }

  // ---------------------------------------------------------------- commands

  function csrfToken() {
    const input = document.querySelector("input[name=csrfmiddlewaretoken]");
    return input ? input.value : "";
  }

  async function send(action, extra = {}) {
    const status = $("command-status");
    status.dataset.state = "sending";
    status.textContent = `${action.replace(/_/g, " ")}: sending…`;
    try {
      const response = await fetch(page.commandUrl, {
        method: "POST",
        credentials: "same-origin",
        headers: { "Content-Type": "application/json", "X-CSRFToken": csrfToken() },
        body: JSON.stringify({ action, ...extra }),
      });
      const body = await response.json().catch(() => ({}));
      if (response.ok) {
        status.dataset.state = "ok";
        const what = body.command ? `command ${body.command.id} ${body.command.status.toLowerCase()}`
          : `order ${body.order.id} ${body.order.status.toLowerCase()}`;
        status.textContent = `${action.replace(/_/g, " ")}: ${what}`;
      } else {
        status.dataset.state = "refused";
        status.textContent = `${action.replace(/_/g, " ")}: ${body.detail || response.statusText}`;
      }
    } catch (error) {
      status.dataset.state = "refused";
      status.textContent = `${action.replace(/_/g, " ")}: the server did not answer`;
    }
  }

  function onButton(event) {
    const button = event.target.closest("button[data-action]");
    if (!button || button.disabled) return;
    const action = button.dataset.action;
    if (action === "init_position") {
      $("init-form").hidden = false;
      $("vmap") && $("vmap").classList.add("picking");
      return;
    }
    if (button.dataset.confirm && !window.confirm(button.dataset.confirm)) return;
    send(action);
  }

  function onInitSubmit(event) {
    event.preventDefault();
    const x = Number($("init-x").value);
    const y = Number($("init-y").value);
    const heading = Number($("init-heading").value) || 0;
    const node = $("init-node").value.trim();
    const map = (pose() && pose().mapId) || page.snapshot.map || (page.layout && page.layout.mapId);
    const question = `Set the position of ${page.snapshot.serial} to x ${x}, y ${y}, ` +
      `heading ${heading}° on map ${map}${node ? ` at node ${node}` : ""}? ` +
      "A wrong position makes the vehicle drive from the wrong place.";
    if (!window.confirm(question)) return;
    send("init_position", { x, y, theta: heading * Math.PI / 180, mapId: map, lastNodeId: node });
    closeInit();
  }

  function closeInit() {
    $("init-form").hidden = true;
    $("vmap") && $("vmap").classList.remove("picking");
    page.pick = null;
    renderPick();
  }

  // ---------------------------------------------------------------- websocket

  function setConnection(stateName, text) {
    const element = $("connection");
    element.dataset.state = stateName;
    element.querySelector(".conn-text").textContent = text;
  }

  function connect() {
    const scheme = window.location.protocol === "https:" ? "wss" : "ws";
    const socket = new WebSocket(`${scheme}://${window.location.host}${page.socketPath}`);
    socketState.socket = socket;
    socket.addEventListener("open", () => {
      socketState.attempts = 0;
      setConnection("live", "live");
      clearInterval(socketState.renew);
      socketState.renew = setInterval(() => {
        if (socket.readyState !== WebSocket.OPEN) return;
        // Nothing yet (the vehicle had not connected since control started): ask for it all.
        socket.send(JSON.stringify({ type: "watch", full: page.latest.size === 0 }));
      }, WATCH_RENEW_MS);
    });
    socket.addEventListener("message", (event) => {
      let message;
      try {
        message = JSON.parse(event.data);
      } catch (error) {
        return;
      }
      if (message.event === "vehicle.messages") onMessages(message.payload || {});
    });
    socket.addEventListener("close", (event) => {
      clearInterval(socketState.renew);
      if (event.code === 4401 || event.code === 4403) {
        setConnection("signed-out", event.code === 4401 ? "signed out" : "not permitted");
        return;
      }
      socketState.attempts += 1;
      const delay = Math.min(RECONNECT_MAX_MS, 1000 * 2 ** Math.min(socketState.attempts, 5));
      setConnection("reconnecting", "reconnecting");
      clearTimeout(socketState.retry);
      socketState.retry = setTimeout(connect, delay);
    });
  }

  // ---------------------------------------------------------------- start

  function start() {
    page.snapshot = readJsonScript("snapshot-data") || {};
    page.layout = readJsonScript("layout-data");
    page.allowed = new Set(readJsonScript("allowed-data") || []);
    const urls = $("vehicle-urls");
    page.commandUrl = urls.dataset.command;
    page.socketPath = urls.dataset.socket;
    const root = $("vmap");
    if (root && page.layout) {
      page.layers = drawLayout(root, page.layout);
      root.addEventListener("click", onMapClick);
    }
    $("buttons").addEventListener("click", onButton);
    $("init-form").addEventListener("submit", onInitSubmit);
    $("init-cancel").addEventListener("click", closeInit);
    $("init-heading").addEventListener("input", renderPick);
    for (const chip of document.querySelectorAll(".chip")) {
      chip.addEventListener("click", () => {
        page.selectedTopic = chip.dataset.topic;
        renderChips();
      });
    }
    $("log-filter").addEventListener("input", () => renderLog(true));
    $("log-filter").addEventListener("submit", (event) => event.preventDefault());
    $("log-table").addEventListener("click", onLogClick);
    renderAll();
    connect();
  }

  if (document.readyState === "loading") {
    document.addEventListener("DOMContentLoaded", start);
  } else {
    start();
  }
})();
