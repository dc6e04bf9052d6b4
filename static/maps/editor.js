// Open Fleet layout editor.
//
// One map's layout drawn on a canvas (SVG gets slow beyond a few thousand elements): the floor
// plan, zones, edges, stations and nodes. The page starts from the JSON in #editor-data and
// keeps the layout in `model` (Maps by id); every change marks it dirty and asks for one redraw
// per animation frame. "Validate" posts the layout as drawn to check/ and lists the findings;
// "Save version" posts it to save/, which writes it atomically as the map's next version.
//
// Coordinates: the layout is in metres with y up; the canvas y points down. The view maps a
// point (x, y) to the screen as (x * scale + ox, -y * scale + oy), scale in pixels per metre.

(() => {
  "use strict";

  const HIT_PX = 8; // how close a click must be to a node, edge or vertex
  const DRAG_PX = 4; // pointer travel that turns a click into a drag
  const INDEX_CELL = 2; // metres per cell of the node index
  const MIN_SCALE = 0.05;
  const MAX_SCALE = 400;
  const FIT_MARGIN_PX = 40;
  const FIT_PADDING_M = 1.5;
  const MAX_FIT_SCALE = 60; // px per metre: a tiny layout is not blown up beyond this
  const HINT_MS = 8000; // a hint fades after this long
  const ARROWS_FROM_SCALE = 6; // px per metre from which one-way arrows are drawn
  const NODE_LABELS_FROM_SCALE = 28;
  const STATION_LABELS_FROM_SCALE = 9;
  const MAX_LABELS = 800;
  const STATION_HALF = 0.45; // metres: half the side of a station's square
  const FLOOR_PLAN_ALPHA = 0.55;

  const KIND_COLORS = {
    PICK: ["#d6ecff", "#2b87d8"],
    DROP: ["#f1e1fb", "#9b4fc9"],
    HANDOVER: ["#e3f4ea", "#2f9a5c"],
    CHARGE: ["#fff1c9", "#d69a00"],
    PARK: ["#e8ebef", "#7d8896"],
    OTHER: ["#f2f2f2", "#5d6b7c"],
  };
  const ZONE_COLORS = {
    BLOCKED: "#d93a3a",
    RESTRICTED: "#e0642b",
    SPEED_LIMIT: "#e08a00",
    DIRECTED: "#2f6fde",
    BIDIRECTED: "#0e9aa7",
    NO_STOPPING: "#d1437f",
    PARKING: "#7d8896",
    CHARGING: "#c9a400",
    LINE_GUIDED: "#7a4ee0",
    RELEASE: "#b35c00",
    COORDINATED_REPLANNING: "#3aa0c8",
    ACTION: "#1f9d55",
    PRIORITY: "#4f9a1f",
    PENALTY: "#8a5a2b",
  };
  const ZONE_DEFAULTS = {
    SPEED_LIMIT: { maxSpeed: 0.5 },
    DIRECTED: { direction: 0, limitation: "RESTRICTED" },
    BIDIRECTED: { direction: 0, limitation: "SOFT" },
    PENALTY: { penaltyFactor: 0.5 },
    PRIORITY: { priorityFactor: 0.5 },
    RELEASE: { releaseLossBehavior: "STOP" },
  };

  const DATA = readJsonScript("editor-data");
  const CSRF_TOKEN = document.querySelector('meta[name="csrf-token"]').content;

  const model = {
    nodes: new Map(), // id -> {id, x, y, theta, name}
    edges: new Map(), // id -> {id, start, end, maxSpeed, name}
    stations: new Map(), // id -> {id, name, kind, nodes: [node ids, primary first]}
    zones: new Map(), // id -> zone (see maps.selectors.zones.zone_as_dict)
    floorPlan: { ...DATA.map.floorPlan },
  };
  const view = { scale: 20, ox: 0, oy: 0, width: 0, height: 0, dpr: 1 };
  const ui = {
    tool: "select",
    selection: null, // {type: "node" | "edge" | "station" | "zone", id}
    hover: null,
    press: null, // the pointer press being handled
    edgeStart: null, // node id the edge tool connects from
    zoneDraft: [], // vertices of the zone being drawn
    pointer: null, // last pointer position in metres
    spaceDown: false,
    dirty: false,
    busy: false,
    baseRevision: DATA.map.revision,
    version: DATA.map.version,
    payloadOrder: null, // ids by list, as last posted (to focus problems by path)
  };
  const derived = { index: null, stationOfNode: null, edgeOfPair: null };
  const taken = {
    nodes: new Set(DATA.takenIds.nodes),
    edges: new Set(DATA.takenIds.edges),
    stations: new Set(DATA.takenIds.stations),
    zones: new Set(), // zone ids are per map
  };
  const stats = { lastDrawMs: 0, draws: 0 };
  const idCounters = new Map(); // "kind:prefix" -> next number to try for a new id
  const elements = {};
  let canvas = null;
  let context = null;
  let floorPlanImage = null;
  let frameRequested = false;
  let hintTimer = 0;

  // ---------------------------------------------------------------- small helpers

  function readJsonScript(id) {
    return JSON.parse(document.getElementById(id).textContent);
  }

  function element(tag, attributes = {}, text = "") {
    const node = document.createElement(tag);
    for (const [name, value] of Object.entries(attributes)) {
      if (name === "className") node.className = value;
      else node.setAttribute(name, String(value));
    }
    if (text) node.textContent = text;
    return node;
  }

  function round(value, digits = 3) {
    const factor = 10 ** digits;
    return Math.round(value * factor) / factor;
  }

  function degrees(radians) {
    return radians === null || radians === undefined ? "" : String(round((radians * 180) / Math.PI, 2));
  }

  function radians(text) {
    return text === "" ? null : (Number(text) * Math.PI) / 180;
  }

  function numberOrNull(text) {
    if (text === "" || text === null) return null;
    const value = Number(text);
    return Number.isFinite(value) ? value : null;
  }

  function plural(count, noun) {
    return `${count} ${noun}${count === 1 ? "" : "s"}`;
  }

  function pairKey(start, end) {
    return `${start}\u0000${end}`;
  }

  function distanceToSegment(px, py, ax, ay, bx, by) {
    const dx = bx - ax;
    const dy = by - ay;
    const squared = dx * dx + dy * dy;
    const t = squared ? Math.max(0, Math.min(1, ((px - ax) * dx + (py - ay) * dy) / squared)) : 0;
    return Math.hypot(px - (ax + t * dx), py - (ay + t * dy));
  }

  function pointInPolygon(x, y, vertices) {
    let inside = false;
    for (let i = 0, j = vertices.length - 1; i < vertices.length; j = i++) {
      const a = vertices[i];
      const b = vertices[j];
      if (a.y > y !== b.y > y && x < ((b.x - a.x) * (y - a.y)) / (b.y - a.y) + a.x) inside = !inside;
    }
    return inside;
  }

  function polygonArea(vertices) {
    let total = 0;
    for (let i = 0, j = vertices.length - 1; i < vertices.length; j = i++) {
      total += vertices[j].x * vertices[i].y - vertices[i].x * vertices[j].y;
    }
    return Math.abs(total / 2);
  }

  function centroid(vertices) {
    const sum = vertices.reduce((acc, v) => ({ x: acc.x + v.x, y: acc.y + v.y }), { x: 0, y: 0 });
    return { x: sum.x / vertices.length, y: sum.y / vertices.length };
  }

  // ---------------------------------------------------------------- model

  function loadModel() {
    for (const node of DATA.nodes) model.nodes.set(node.id, { ...node });
    for (const edge of DATA.edges) model.edges.set(edge.id, { ...edge });
    for (const station of DATA.stations) model.stations.set(station.id, { ...station, nodes: [...station.nodes] });
    for (const zone of DATA.zones) model.zones.set(zone.id, { ...zone, vertices: zone.vertices.map((v) => ({ ...v })) });
  }

  function changed() {
    derived.index = null;
    derived.stationOfNode = null;
    derived.edgeOfPair = null;
    setDirty(true);
    requestDraw();
  }

  function nodeIndex() {
    if (!derived.index) {
      const cells = new Map();
      for (const node of model.nodes.values()) {
        const key = `${Math.floor(node.x / INDEX_CELL)},${Math.floor(node.y / INDEX_CELL)}`;
        if (!cells.has(key)) cells.set(key, []);
        cells.get(key).push(node);
      }
      derived.index = cells;
    }
    return derived.index;
  }

  function stationOfNode() {
    if (!derived.stationOfNode) {
      derived.stationOfNode = new Map();
      for (const station of model.stations.values()) {
        for (const nodeId of station.nodes) {
          if (!derived.stationOfNode.has(nodeId)) derived.stationOfNode.set(nodeId, station.id);
        }
      }
    }
    return derived.stationOfNode;
  }

  function edgeOfPair() {
    if (!derived.edgeOfPair) {
      derived.edgeOfPair = new Map();
      for (const edge of model.edges.values()) derived.edgeOfPair.set(pairKey(edge.start, edge.end), edge.id);
    }
    return derived.edgeOfPair;
  }

  function isTaken(kind, id) {
    return model[kind].has(id) || taken[kind].has(id);
  }

  function freshId(kind, prefix) {
    const key = `${kind}:${prefix}`;
    let number = idCounters.get(key) || 1;
    while (isTaken(kind, `${prefix}${number}`)) number += 1;
    idCounters.set(key, number + 1);
    return `${prefix}${number}`;
  }

  function freshEdgeId(start, end) {
    const base = `${start}-${end}`;
    let id = base;
    for (let n = 2; isTaken("edges", id); n += 1) id = `${base}~${n}`;
    return id;
  }

  function snap(value) {
    const step = Number(elements.snap.value);
    return step ? Math.round(value / step) * step : round(value);
  }

  function addNode(x, y) {
    const node = { id: freshId("nodes", "N"), x: snap(x), y: snap(y), theta: null, name: "" };
    model.nodes.set(node.id, node);
    changed();
    return node;
  }

  function addEdge(start, end) {
    if (start === end || edgeOfPair().has(pairKey(start, end))) return null;
    const edge = { id: freshEdgeId(start, end), start, end, maxSpeed: null, name: "" };
    model.edges.set(edge.id, edge);
    changed();
    return edge;
  }

  function connect(start, end) {
    const forward = addEdge(start, end) || model.edges.get(edgeOfPair().get(pairKey(start, end)));
    if (elements.twoWay.checked) addEdge(end, start);
    return forward;
  }

  function addStation(nodeId, kind) {
    const station = { id: freshId("stations", `${kind}-`), name: "", kind, nodes: [nodeId] };
    station.name = station.id;
    model.stations.set(station.id, station);
    changed();
    return station;
  }

  function addZone(vertices, type) {
    const zone = {
      id: freshId("zones", "Z"),
      name: "",
      description: "",
      type,
      enabled: true,
      vertices,
      maxSpeed: null,
      direction: null,
      limitation: "",
      penaltyFactor: null,
      priorityFactor: null,
      releaseLossBehavior: "",
      entryActions: [],
      duringActions: [],
      exitActions: [],
      vehicleTypes: [],
      ...(ZONE_DEFAULTS[type] || {}),
    };
    model.zones.set(zone.id, zone);
    changed();
    return zone;
  }

  function deleteNode(nodeId) {
    for (const edge of [...model.edges.values()]) {
      if (edge.start === nodeId || edge.end === nodeId) model.edges.delete(edge.id);
    }
    for (const station of [...model.stations.values()]) {
      station.nodes = station.nodes.filter((id) => id !== nodeId);
      if (!station.nodes.length) model.stations.delete(station.id);
    }
    model.nodes.delete(nodeId);
  }

  function deleteSelection() {
    const selection = ui.selection;
    if (!selection) return;
    if (selection.type === "node") deleteNode(selection.id);
    else model[`${selection.type}s`].delete(selection.id);
    select(null);
    changed();
  }

  function renameNode(node, newId) {
    model.nodes.delete(node.id);
    for (const edge of model.edges.values()) {
      if (edge.start === node.id) edge.start = newId;
      if (edge.end === node.id) edge.end = newId;
    }
    for (const station of model.stations.values()) {
      station.nodes = station.nodes.map((id) => (id === node.id ? newId : id));
    }
    node.id = newId;
    model.nodes.set(newId, node);
  }

  function renameElement(kind, item, newId) {
    const clean = newId.trim();
    if (!clean || clean === item.id) return false;
    if (isTaken(kind, clean)) {
      setStatus(`${clean} is taken already`, "error");
      return false;
    }
    if (kind === "nodes") renameNode(item, clean);
    else {
      model[kind].delete(item.id);
      item.id = clean;
      model[kind].set(clean, item);
    }
    ui.selection = { type: kind.slice(0, -1), id: clean };
    changed();
    return true;
  }

  // ---------------------------------------------------------------- view

  function toScreen(x, y) {
    return [x * view.scale + view.ox, -y * view.scale + view.oy];
  }

  function toWorld(sx, sy) {
    return [(sx - view.ox) / view.scale, -(sy - view.oy) / view.scale];
  }

  function visibleBounds() {
    const [minX, maxY] = toWorld(0, 0);
    const [maxX, minY] = toWorld(view.width, view.height);
    return { minX, minY, maxX, maxY };
  }

  function resizeCanvas() {
    const box = elements.wrap.getBoundingClientRect();
    view.dpr = window.devicePixelRatio || 1;
    view.width = Math.max(1, box.width);
    view.height = Math.max(1, box.height);
    canvas.width = Math.round(view.width * view.dpr);
    canvas.height = Math.round(view.height * view.dpr);
    requestDraw();
  }

  function layoutBounds() {
    const xs = [];
    const ys = [];
    for (const node of model.nodes.values()) {
      xs.push(node.x);
      ys.push(node.y);
    }
    for (const zone of model.zones.values()) {
      for (const v of zone.vertices) {
        xs.push(v.x);
        ys.push(v.y);
      }
    }
    if (!xs.length) return { minX: -2, minY: -2, maxX: 20, maxY: 14 };
    const pad = FIT_PADDING_M; // station squares and their labels reach past the nodes
    return {
      minX: Math.min(...xs) - pad, minY: Math.min(...ys) - pad,
      maxX: Math.max(...xs) + pad, maxY: Math.max(...ys) + pad,
    };
  }

  function fitView(bounds = layoutBounds()) {
    const width = Math.max(bounds.maxX - bounds.minX, 1);
    const height = Math.max(bounds.maxY - bounds.minY, 1);
    const scale = Math.min(
      (view.width - 2 * FIT_MARGIN_PX) / width,
      (view.height - 2 * FIT_MARGIN_PX) / height,
      MAX_FIT_SCALE,
    );
    view.scale = Math.max(MIN_SCALE, Math.min(MAX_SCALE, scale));
    view.ox = view.width / 2 - ((bounds.minX + bounds.maxX) / 2) * view.scale;
    view.oy = view.height / 2 + ((bounds.minY + bounds.maxY) / 2) * view.scale;
    requestDraw();
  }

  function zoomAt(sx, sy, factor) {
    const scale = Math.max(MIN_SCALE, Math.min(MAX_SCALE, view.scale * factor));
    const [x, y] = toWorld(sx, sy);
    view.scale = scale;
    view.ox = sx - x * scale;
    view.oy = sy + y * scale;
    requestDraw();
  }

  function centreOn(x, y) {
    view.scale = Math.max(view.scale, 30);
    view.ox = view.width / 2 - x * view.scale;
    view.oy = view.height / 2 + y * view.scale;
    requestDraw();
  }

  // ---------------------------------------------------------------- drawing

  function requestDraw() {
    if (frameRequested) return;
    frameRequested = true;
    requestAnimationFrame(() => {
      frameRequested = false;
      draw();
    });
  }

  function draw() {
    const started = performance.now();
    const ctx = context;
    ctx.setTransform(view.dpr, 0, 0, view.dpr, 0, 0);
    ctx.fillStyle = "#f8fafc";
    ctx.fillRect(0, 0, view.width, view.height);
    const bounds = visibleBounds();
    drawGrid(ctx, bounds);
    ctx.setTransform(view.dpr * view.scale, 0, 0, -view.dpr * view.scale, view.dpr * view.ox, view.dpr * view.oy);
    drawFloorPlan(ctx);
    drawZones(ctx);
    drawEdges(ctx, bounds);
    drawStations(ctx, bounds);
    drawNodes(ctx, bounds);
    drawSelection(ctx);
    drawPending(ctx);
    ctx.setTransform(view.dpr, 0, 0, view.dpr, 0, 0);
    drawLabels(ctx, bounds);
    stats.lastDrawMs = performance.now() - started;
    stats.draws += 1;
    updateStatusbar();
  }

  function px(pixels) {
    return pixels / view.scale;
  }

  function drawGrid(ctx, bounds) {
    const step = gridStep();
    ctx.strokeStyle = "#e9eef3";
    ctx.lineWidth = 1;
    ctx.beginPath();
    for (let x = Math.floor(bounds.minX / step) * step; x <= bounds.maxX; x += step) {
      const [sx] = toScreen(x, 0);
      ctx.moveTo(Math.round(sx) + 0.5, 0);
      ctx.lineTo(Math.round(sx) + 0.5, view.height);
    }
    for (let y = Math.floor(bounds.minY / step) * step; y <= bounds.maxY; y += step) {
      const [, sy] = toScreen(0, y);
      ctx.moveTo(0, Math.round(sy) + 0.5);
      ctx.lineTo(view.width, Math.round(sy) + 0.5);
    }
    ctx.stroke();
  }

  function gridStep() {
    const candidates = [0.5, 1, 2, 5, 10, 20, 50, 100, 200, 500];
    return candidates.find((step) => step * view.scale >= 24) || 1000;
  }

  function drawFloorPlan(ctx) {
    const plan = model.floorPlan;
    if (!floorPlanImage || !floorPlanImage.complete || !floorPlanImage.naturalWidth || !plan.scale) return;
    ctx.save();
    ctx.translate(plan.originX || 0, plan.originY || 0);
    ctx.rotate(plan.rotation || 0);
    ctx.scale(plan.scale, -plan.scale);
    ctx.translate(0, -floorPlanImage.naturalHeight);
    ctx.globalAlpha = FLOOR_PLAN_ALPHA;
    ctx.drawImage(floorPlanImage, 0, 0);
    ctx.restore();
  }

  function drawZones(ctx) {
    for (const zone of model.zones.values()) {
      if (zone.vertices.length < 2) continue;
      const color = ZONE_COLORS[zone.type] || "#5d6b7c";
      tracePolygon(ctx, zone.vertices);
      ctx.globalAlpha = zone.enabled ? 0.16 : 0.06;
      ctx.fillStyle = color;
      ctx.fill();
      ctx.globalAlpha = zone.enabled ? 0.9 : 0.4;
      ctx.strokeStyle = color;
      ctx.lineWidth = px(1.5);
      ctx.setLineDash(zone.enabled ? [] : [px(6), px(4)]);
      ctx.stroke();
      ctx.setLineDash([]);
      ctx.globalAlpha = 1;
      if ((zone.type === "DIRECTED" || zone.type === "BIDIRECTED") && zone.direction !== null) {
        drawDirection(ctx, zone, color);
      }
    }
  }

  function tracePolygon(ctx, vertices) {
    ctx.beginPath();
    vertices.forEach((v, i) => (i ? ctx.lineTo(v.x, v.y) : ctx.moveTo(v.x, v.y)));
    ctx.closePath();
  }

  function drawDirection(ctx, zone, color) {
    const middle = centroid(zone.vertices);
    const length = px(36);
    const dx = Math.cos(zone.direction) * length;
    const dy = Math.sin(zone.direction) * length;
    ctx.strokeStyle = color;
    ctx.fillStyle = color;
    ctx.lineWidth = px(3);
    ctx.beginPath();
    ctx.moveTo(middle.x - dx / 2, middle.y - dy / 2);
    ctx.lineTo(middle.x + dx / 2, middle.y + dy / 2);
    ctx.stroke();
    arrowHead(ctx, middle.x + dx / 2, middle.y + dy / 2, zone.direction, px(10));
    if (zone.type === "BIDIRECTED") arrowHead(ctx, middle.x - dx / 2, middle.y - dy / 2, zone.direction + Math.PI, px(10));
  }

  function arrowHead(ctx, x, y, angle, size) {
    ctx.beginPath();
    ctx.moveTo(x, y);
    ctx.lineTo(x - size * Math.cos(angle - 0.45), y - size * Math.sin(angle - 0.45));
    ctx.lineTo(x - size * Math.cos(angle + 0.45), y - size * Math.sin(angle + 0.45));
    ctx.closePath();
    ctx.fill();
  }

  function edgeVisible(a, b, bounds) {
    return !(
      Math.max(a.x, b.x) < bounds.minX || Math.min(a.x, b.x) > bounds.maxX ||
      Math.max(a.y, b.y) < bounds.minY || Math.min(a.y, b.y) > bounds.maxY
    );
  }

  function drawEdges(ctx, bounds) {
    const pairs = edgeOfPair();
    const oneWay = [];
    ctx.strokeStyle = "#8d9bab";
    ctx.lineWidth = px(Math.max(1.2, Math.min(3, view.scale * 0.07)));
    ctx.lineCap = "round";
    ctx.beginPath();
    for (const edge of model.edges.values()) {
      const a = model.nodes.get(edge.start);
      const b = model.nodes.get(edge.end);
      if (!a || !b || !edgeVisible(a, b, bounds)) continue;
      const reverse = pairs.has(pairKey(edge.end, edge.start));
      if (reverse && edge.start > edge.end) continue; // a two-way pair is drawn once
      if (!reverse) oneWay.push([a, b]);
      ctx.moveTo(a.x, a.y);
      ctx.lineTo(b.x, b.y);
    }
    ctx.stroke();
    if (view.scale >= ARROWS_FROM_SCALE) drawOneWayArrows(ctx, oneWay);
  }

  function drawOneWayArrows(ctx, segments) {
    ctx.fillStyle = "#5d6b7c";
    for (const [a, b] of segments) {
      const angle = Math.atan2(b.y - a.y, b.x - a.x);
      const size = px(Math.min(12, Math.max(7, view.scale * 0.35)));
      arrowHead(ctx, (a.x + b.x) / 2 + (Math.cos(angle) * size) / 2, (a.y + b.y) / 2 + (Math.sin(angle) * size) / 2, angle, size);
    }
  }

  function stationHalf() {
    return Math.max(STATION_HALF, px(6));
  }

  function drawStations(ctx, bounds) {
    const half = stationHalf();
    ctx.lineWidth = px(1.5);
    for (const station of model.stations.values()) {
      const node = model.nodes.get(station.nodes[0]);
      if (!node || node.x < bounds.minX - half || node.x > bounds.maxX + half) continue;
      const [fill, stroke] = KIND_COLORS[station.kind] || KIND_COLORS.OTHER;
      ctx.fillStyle = fill;
      ctx.strokeStyle = stroke;
      ctx.fillRect(node.x - half, node.y - half, 2 * half, 2 * half);
      ctx.strokeRect(node.x - half, node.y - half, 2 * half, 2 * half);
    }
  }

  function nodeRadius() {
    return Math.max(px(2.5), Math.min(0.16, px(6)));
  }

  function drawNodes(ctx, bounds) {
    const radius = nodeRadius();
    ctx.fillStyle = "#45546a";
    ctx.beginPath();
    for (const node of model.nodes.values()) {
      if (node.x < bounds.minX - radius || node.x > bounds.maxX + radius) continue;
      if (node.y < bounds.minY - radius || node.y > bounds.maxY + radius) continue;
      ctx.moveTo(node.x + radius, node.y);
      ctx.arc(node.x, node.y, radius, 0, 2 * Math.PI);
    }
    ctx.fill();
  }

  function drawSelection(ctx) {
    for (const [item, color] of [[ui.hover, "rgba(47,111,222,0.45)"], [ui.selection, "#2f6fde"]]) {
      if (item) highlight(ctx, item, color);
    }
    if (ui.edgeStart && model.nodes.has(ui.edgeStart)) {
      const node = model.nodes.get(ui.edgeStart);
      ctx.strokeStyle = "#1f9d55";
      ctx.lineWidth = px(3);
      ctx.beginPath();
      ctx.arc(node.x, node.y, px(9), 0, 2 * Math.PI);
      ctx.stroke();
    }
  }

  function highlight(ctx, item, color) {
    ctx.strokeStyle = color;
    ctx.fillStyle = color;
    ctx.lineWidth = px(3);
    if (item.type === "node" && model.nodes.has(item.id)) {
      const node = model.nodes.get(item.id);
      ctx.beginPath();
      ctx.arc(node.x, node.y, nodeRadius() + px(4), 0, 2 * Math.PI);
      ctx.stroke();
    } else if (item.type === "edge" && model.edges.has(item.id)) {
      const edge = model.edges.get(item.id);
      const a = model.nodes.get(edge.start);
      const b = model.nodes.get(edge.end);
      ctx.lineWidth = px(5);
      ctx.beginPath();
      ctx.moveTo(a.x, a.y);
      ctx.lineTo(b.x, b.y);
      ctx.stroke();
      arrowHead(ctx, (a.x + b.x) / 2, (a.y + b.y) / 2, Math.atan2(b.y - a.y, b.x - a.x), px(14));
    } else if (item.type === "station" && model.stations.has(item.id)) {
      const node = model.nodes.get(model.stations.get(item.id).nodes[0]);
      const half = stationHalf() + px(3);
      if (node) ctx.strokeRect(node.x - half, node.y - half, 2 * half, 2 * half);
    } else if (item.type === "zone" && model.zones.has(item.id)) {
      const zone = model.zones.get(item.id);
      tracePolygon(ctx, zone.vertices);
      ctx.stroke();
      if (item === ui.selection) drawVertexHandles(ctx, zone.vertices, color);
    }
  }

  function drawVertexHandles(ctx, vertices, color) {
    const half = px(4);
    ctx.fillStyle = "#fff";
    ctx.strokeStyle = color;
    ctx.lineWidth = px(1.5);
    for (const v of vertices) {
      ctx.fillRect(v.x - half, v.y - half, 2 * half, 2 * half);
      ctx.strokeRect(v.x - half, v.y - half, 2 * half, 2 * half);
    }
  }

  function drawPending(ctx) {
    const pointer = ui.pointer;
    if (ui.tool === "edge" && ui.edgeStart && pointer && model.nodes.has(ui.edgeStart)) {
      const start = model.nodes.get(ui.edgeStart);
      ctx.strokeStyle = "#1f9d55";
      ctx.lineWidth = px(2);
      ctx.setLineDash([px(6), px(4)]);
      ctx.beginPath();
      ctx.moveTo(start.x, start.y);
      ctx.lineTo(pointer[0], pointer[1]);
      ctx.stroke();
      ctx.setLineDash([]);
    }
    if (ui.tool === "zone" && ui.zoneDraft.length) {
      const color = ZONE_COLORS[elements.zoneType.value] || "#2f6fde";
      ctx.strokeStyle = color;
      ctx.lineWidth = px(2);
      ctx.beginPath();
      ui.zoneDraft.forEach((v, i) => (i ? ctx.lineTo(v.x, v.y) : ctx.moveTo(v.x, v.y)));
      if (pointer) ctx.lineTo(pointer[0], pointer[1]);
      ctx.stroke();
      drawVertexHandles(ctx, ui.zoneDraft, color);
    }
  }

  function drawLabels(ctx, bounds) {
    ctx.font = "600 11px system-ui, sans-serif";
    ctx.textAlign = "center";
    ctx.textBaseline = "middle";
    ctx.lineJoin = "round";
    ctx.lineWidth = 3;
    ctx.strokeStyle = "rgba(255,255,255,0.9)";
    let budget = MAX_LABELS;
    if (view.scale >= STATION_LABELS_FROM_SCALE) budget = labelStations(ctx, bounds, budget);
    if (view.scale >= NODE_LABELS_FROM_SCALE) budget = labelNodes(ctx, bounds, budget);
    labelZones(ctx);
  }

  function inside(bounds, x, y) {
    return x >= bounds.minX && x <= bounds.maxX && y >= bounds.minY && y <= bounds.maxY;
  }

  function label(ctx, text, sx, sy, color) {
    ctx.strokeText(text, sx, sy);
    ctx.fillStyle = color;
    ctx.fillText(text, sx, sy);
  }

  function labelStations(ctx, bounds, budget) {
    const offset = stationHalf() * view.scale + 9;
    for (const station of model.stations.values()) {
      const node = model.nodes.get(station.nodes[0]);
      if (!node || !inside(bounds, node.x, node.y) || budget-- <= 0) continue;
      const [sx, sy] = toScreen(node.x, node.y);
      label(ctx, station.name || station.id, sx, sy - offset, "#17202b");
    }
    return budget;
  }

  function labelNodes(ctx, bounds, budget) {
    ctx.font = "10px system-ui, sans-serif";
    const stations = stationOfNode();
    for (const node of model.nodes.values()) {
      if (stations.has(node.id) || !inside(bounds, node.x, node.y) || budget-- <= 0) continue;
      const [sx, sy] = toScreen(node.x, node.y);
      label(ctx, node.id, sx, sy + 12, "#5d6b7c");
    }
    return budget;
  }

  function labelZones(ctx) {
    ctx.font = "600 11px system-ui, sans-serif";
    for (const zone of model.zones.values()) {
      if (zone.vertices.length < 3 || polygonArea(zone.vertices) * view.scale * view.scale < 900) continue;
      const middle = centroid(zone.vertices);
      const [sx, sy] = toScreen(middle.x, middle.y);
      const speed = zone.type === "SPEED_LIMIT" && zone.maxSpeed ? ` ${zone.maxSpeed} m/s` : "";
      const text = `${zone.name || zone.id} · ${zone.type.toLowerCase().replace(/_/g, " ")}${speed}`;
      label(ctx, text, sx, sy - 14, ZONE_COLORS[zone.type] || "#17202b");
    }
  }

  // ---------------------------------------------------------------- hit testing

  function nodeAt(x, y, radiusPx = HIT_PX) {
    const radius = Math.max(radiusPx / view.scale, nodeRadius());
    const cells = nodeIndex();
    let best = null;
    let bestDistance = radius;
    const reach = Math.ceil(radius / INDEX_CELL);
    const cx = Math.floor(x / INDEX_CELL);
    const cy = Math.floor(y / INDEX_CELL);
    for (let i = cx - reach; i <= cx + reach; i += 1) {
      for (let j = cy - reach; j <= cy + reach; j += 1) {
        for (const node of cells.get(`${i},${j}`) || []) {
          const distance = Math.hypot(node.x - x, node.y - y);
          if (distance <= bestDistance) {
            best = node;
            bestDistance = distance;
          }
        }
      }
    }
    return best;
  }

  function stationAt(x, y) {
    const half = stationHalf();
    for (const station of model.stations.values()) {
      const node = model.nodes.get(station.nodes[0]);
      if (node && Math.abs(node.x - x) <= half && Math.abs(node.y - y) <= half) return station;
    }
    return null;
  }

  function edgeAt(x, y) {
    const limit = HIT_PX / view.scale;
    let best = null;
    let bestDistance = limit;
    for (const edge of model.edges.values()) {
      const a = model.nodes.get(edge.start);
      const b = model.nodes.get(edge.end);
      if (!a || !b) continue;
      const distance = distanceToSegment(x, y, a.x, a.y, b.x, b.y);
      if (distance <= bestDistance) {
        best = edge;
        bestDistance = distance;
      }
    }
    return best;
  }

  function zoneAt(x, y) {
    const hits = [...model.zones.values()].filter((zone) => pointInPolygon(x, y, zone.vertices));
    hits.sort((a, b) => polygonArea(a.vertices) - polygonArea(b.vertices));
    return hits[0] || null;
  }

  function vertexAt(x, y) {
    if (!ui.selection || ui.selection.type !== "zone") return null;
    const zone = model.zones.get(ui.selection.id);
    if (!zone) return null;
    const limit = HIT_PX / view.scale;
    const index = zone.vertices.findIndex((v) => Math.hypot(v.x - x, v.y - y) <= limit);
    return index >= 0 ? { zone, index } : null;
  }

  function hitTest(x, y) {
    const node = nodeAt(x, y);
    if (node) return { type: "node", id: node.id };
    const station = stationAt(x, y);
    if (station) return { type: "station", id: station.id };
    const edge = edgeAt(x, y);
    if (edge) return { type: "edge", id: edge.id };
    const zone = zoneAt(x, y);
    return zone ? { type: "zone", id: zone.id } : null;
  }

  // ---------------------------------------------------------------- pointer and keys

  function eventPoint(event) {
    const box = canvas.getBoundingClientRect();
    return [event.clientX - box.left, event.clientY - box.top];
  }

  function onPointerDown(event) {
    canvas.focus();
    const [sx, sy] = eventPoint(event);
    const [x, y] = toWorld(sx, sy);
    const pan = event.button === 1 || (event.button === 0 && ui.spaceDown);
    if (event.button !== 0 && !pan) return;
    canvas.setPointerCapture(event.pointerId);
    ui.press = { sx, sy, x, y, moved: false, mode: pan ? "pan" : pressMode(x, y), origin: [view.ox, view.oy] };
    event.preventDefault();
  }

  function pressMode(x, y) {
    if (ui.tool !== "select") return "click";
    const vertex = vertexAt(x, y);
    if (vertex) return { vertex };
    const node = nodeAt(x, y);
    if (node) return { node: node.id };
    return "click";
  }

  function onPointerMove(event) {
    const [sx, sy] = eventPoint(event);
    const [x, y] = toWorld(sx, sy);
    ui.pointer = [x, y];
    const press = ui.press;
    if (press && !press.moved && Math.hypot(sx - press.sx, sy - press.sy) >= DRAG_PX) press.moved = true;
    if (press && press.moved) dragTo(press, sx, sy, x, y);
    else updateHover(x, y);
    requestDraw();
  }

  function dragTo(press, sx, sy, x, y) {
    if (press.mode === "pan" || press.mode === "click") {
      view.ox = press.origin[0] + (sx - press.sx);
      view.oy = press.origin[1] + (sy - press.sy);
    } else if (press.mode.node) {
      const node = model.nodes.get(press.mode.node);
      node.x = snap(x);
      node.y = snap(y);
      ui.selection = { type: "node", id: node.id };
      setDirty(true);
    } else if (press.mode.vertex) {
      const { zone, index } = press.mode.vertex;
      zone.vertices[index] = { x: snap(x), y: snap(y) };
      setDirty(true);
    }
  }

  function onPointerUp(event) {
    const press = ui.press;
    ui.press = null;
    if (!press) return;
    if (canvas.hasPointerCapture(event.pointerId)) canvas.releasePointerCapture(event.pointerId);
    if (!press.moved && press.mode !== "pan") {
      clickAt(press.x, press.y);
    } else if (press.mode.node || press.mode.vertex) {
      changed();
      renderProperties();
    }
  }

  function updateHover(x, y) {
    const hit = ui.tool === "zone" ? null : hitTest(x, y);
    const same = hit && ui.hover && hit.type === ui.hover.type && hit.id === ui.hover.id;
    if (!same && (hit || ui.hover)) ui.hover = hit;
    canvas.style.cursor = hit && ui.tool === "select" ? "pointer" : "";
  }

  function clickAt(x, y) {
    const handlers = { select: clickSelect, node: clickNode, edge: clickEdge, station: clickStation, zone: clickZone };
    handlers[ui.tool](x, y);
    requestDraw();
  }

  function clickSelect(x, y) {
    select(hitTest(x, y));
  }

  function clickNode(x, y) {
    const node = nodeAt(x, y);
    select({ type: "node", id: (node || addNode(x, y)).id });
  }

  function clickEdge(x, y) {
    const hit = nodeAt(x, y);
    const node = hit || addNode(x, y);
    if (ui.edgeStart && ui.edgeStart !== node.id) {
      const edge = connect(ui.edgeStart, node.id);
      if (edge) select({ type: "edge", id: edge.id });
    } else if (ui.edgeStart === node.id) {
      ui.edgeStart = null;
      setHint(toolHint());
      return;
    }
    ui.edgeStart = node.id;
    setHint(`From ${node.id}: click the next node (or empty space for a new one). Esc ends.`);
  }

  function clickStation(x, y) {
    const node = nodeAt(x, y);
    if (!node) {
      setHint("Click a node to put a station on it.");
      return;
    }
    const existing = stationOfNode().get(node.id);
    const station = existing ? model.stations.get(existing) : addStation(node.id, elements.stationKind.value);
    select({ type: "station", id: station.id });
  }

  function clickZone(x, y) {
    const draft = ui.zoneDraft;
    const first = draft[0];
    if (draft.length >= 3 && Math.hypot(first.x - x, first.y - y) * view.scale <= HIT_PX + 2) {
      finishZone();
      return;
    }
    draft.push({ x: snap(x), y: snap(y) });
    setHint(`${draft.length} corner(s): click the first corner, double-click or press Enter to close; Backspace removes the last.`);
  }

  function finishZone() {
    if (ui.zoneDraft.length < 3) {
      setHint("A zone needs at least three corners.");
      return;
    }
    const zone = addZone(ui.zoneDraft, elements.zoneType.value);
    ui.zoneDraft = [];
    setHint(toolHint());
    select({ type: "zone", id: zone.id });
  }

  function onWheel(event) {
    event.preventDefault();
    const [sx, sy] = eventPoint(event);
    const delta = event.deltaMode === 1 ? event.deltaY * 16 : event.deltaY;
    zoomAt(sx, sy, Math.exp(-delta * 0.0015));
  }

  function onDoubleClick(event) {
    if (ui.tool !== "zone") return;
    event.preventDefault();
    if (ui.zoneDraft.length > 3) ui.zoneDraft.pop(); // the second click of the double click
    finishZone();
  }

  function typing(event) {
    const target = event.target;
    return target && (target.tagName === "INPUT" || target.tagName === "SELECT" || target.tagName === "TEXTAREA");
  }

  function onKeyDown(event) {
    if ((event.ctrlKey || event.metaKey) && event.key.toLowerCase() === "s") {
      event.preventDefault();
      save();
      return;
    }
    if (typing(event) || event.ctrlKey || event.metaKey || event.altKey) return;
    const tools = { v: "select", n: "node", e: "edge", s: "station", z: "zone" };
    const key = event.key.toLowerCase();
    if (tools[key]) setTool(tools[key]);
    else if (key === "f") fitView();
    else if (key === " ") ui.spaceDown = true;
    else if (key === "escape") cancelPending();
    else if (key === "enter" && ui.tool === "zone") finishZone();
    else if (key === "delete" || key === "backspace") removeSomething();
    else return;
    event.preventDefault();
    requestDraw();
  }

  function onKeyUp(event) {
    if (event.key === " ") ui.spaceDown = false;
  }

  function cancelPending() {
    if (ui.edgeStart || ui.zoneDraft.length) {
      ui.edgeStart = null;
      ui.zoneDraft = [];
      setHint(toolHint());
    } else {
      select(null);
    }
  }

  function removeSomething() {
    if (ui.tool === "zone" && ui.zoneDraft.length) ui.zoneDraft.pop();
    else deleteSelection();
  }

  // ---------------------------------------------------------------- tools, selection, status

  function setTool(tool) {
    ui.tool = tool;
    ui.edgeStart = null;
    ui.zoneDraft = [];
    ui.hover = null;
    for (const button of document.querySelectorAll(".tool[data-tool]")) {
      button.setAttribute("aria-pressed", String(button.dataset.tool === tool));
    }
    for (const option of document.querySelectorAll(".tool-option[data-for]")) {
      option.hidden = option.dataset.for !== tool;
    }
    canvas.dataset.tool = tool;
    setHint(toolHint());
    requestDraw();
  }

  function toolHint() {
    return {
      select: "Click to select, drag a node or zone corner to move it, drag empty space to pan, wheel to zoom.",
      node: "Click to add a node.",
      edge: "Click a node, then the next one to connect them (or empty space for a new node).",
      station: "Click a node to put a station of the chosen kind on it.",
      zone: "Click the corners of the zone; click the first corner or press Enter to close it.",
    }[ui.tool];
  }

  function setHint(text) {
    elements.hint.textContent = text || "";
    clearTimeout(hintTimer);
    hintTimer = setTimeout(() => { elements.hint.textContent = ""; }, HINT_MS);
  }

  function select(item) {
    ui.selection = item;
    renderProperties();
    requestDraw();
  }

  function setDirty(dirty) {
    ui.dirty = dirty;
    if (dirty) setStatus("unsaved changes", "dirty");
  }

  function setStatus(text, state) {
    elements.status.textContent = text;
    elements.status.dataset.state = state;
  }

  function updateStatusbar() {
    const pointer = ui.pointer;
    elements.cursor.textContent = pointer ? `x ${pointer[0].toFixed(2)} m  y ${pointer[1].toFixed(2)} m` : "–";
    elements.counts.textContent = [
      plural(model.nodes.size, "node"), plural(model.edges.size, "edge"),
      plural(model.stations.size, "station"), plural(model.zones.size, "zone"),
    ].join(" · ");
    elements.zoom.textContent = `${view.scale >= 10 ? Math.round(view.scale) : view.scale.toFixed(1)} px/m · ${stats.lastDrawMs.toFixed(1)} ms`;
  }

  function focusOn(type, id) {
    const collection = model[`${type}s`];
    if (!collection || !collection.has(id)) return;
    const item = collection.get(id);
    let point = null;
    if (type === "node") point = item;
    else if (type === "edge") {
      const a = model.nodes.get(item.start);
      const b = model.nodes.get(item.end);
      point = { x: (a.x + b.x) / 2, y: (a.y + b.y) / 2 };
    } else if (type === "station") point = model.nodes.get(item.nodes[0]);
    else if (type === "zone") point = centroid(item.vertices);
    if (point) centreOn(point.x, point.y);
    select({ type, id });
  }

  // ---------------------------------------------------------------- properties panel

  function renderProperties() {
    const panel = elements.properties;
    panel.replaceChildren();
    const selection = ui.selection;
    const item = selection && model[`${selection.type}s`].get(selection.id);
    if (!item) {
      renderMapProperties(panel);
      return;
    }
    const renderers = { node: renderNode, edge: renderEdge, station: renderStation, zone: renderZone };
    renderers[selection.type](panel, item);
  }

  function form(panel, title) {
    panel.append(element("h3", { className: "prop-title" }, title));
    const grid = element("div", { className: "prop-grid" });
    panel.append(grid);
    return grid;
  }

  function field(grid, labelText, input, note = "") {
    const id = `prop-${grid.children.length}`;
    input.id = id;
    grid.append(element("label", { for: id }, labelText));
    const cell = element("div");
    cell.append(input);
    if (note) cell.append(element("p", { className: "help" }, note));
    grid.append(cell);
    return input;
  }

  function textInput(value, onChange, attributes = {}) {
    const input = element("input", { type: "text", value: value ?? "", ...attributes });
    input.addEventListener("change", () => onChange(input.value));
    return input;
  }

  function numberInput(value, onChange, attributes = {}) {
    const input = element("input", { type: "number", step: "any", value: value ?? "", ...attributes });
    input.addEventListener("change", () => onChange(input.value));
    return input;
  }

  function selectInput(choices, value, onChange) {
    const input = element("select");
    for (const [choice, text] of choices) {
      const option = element("option", { value: choice }, text);
      if (choice === value) option.selected = true;
      input.append(option);
    }
    input.addEventListener("change", () => onChange(input.value));
    return input;
  }

  function button(text, onClick, className = "button") {
    const result = element("button", { type: "button", className }, text);
    result.addEventListener("click", onClick);
    return result;
  }

  function actions(panel, ...buttons) {
    const row = element("div", { className: "prop-actions" });
    row.append(...buttons);
    panel.append(row);
  }

  function update(item, key, value) {
    item[key] = value;
    changed();
  }

  function renderMapProperties(panel) {
    const info = DATA.map;
    const grid = form(panel, `Map ${info.mapId}`);
    field(grid, "Site", element("span", {}, info.site || "–"));
    field(grid, "Version", element("span", { id: "map-version" }, ui.version ? String(ui.version) : "not saved here yet"));
    field(grid, "Transitions", element("span", {}, `${DATA.transitions} edge(s) to other floors (kept as they are)`));
    const plan = model.floorPlan;
    const planGrid = form(panel, "Floor plan");
    if (!plan.url) {
      const link = element("a", { href: DATA.urls.admin }, "upload one in the admin");
      const note = element("span", {}, "none: ");
      note.append(link);
      field(planGrid, "Image", note);
    } else {
      field(planGrid, "Scale", numberInput(plan.scale, (v) => update(plan, "scale", numberOrNull(v)), { min: "0" }), "metres per pixel");
      field(planGrid, "Origin x", numberInput(plan.originX, (v) => update(plan, "originX", numberOrNull(v) || 0)), "m, bottom-left corner");
      field(planGrid, "Origin y", numberInput(plan.originY, (v) => update(plan, "originY", numberOrNull(v) || 0)), "m");
      field(planGrid, "Rotation", numberInput(degrees(plan.rotation), (v) => update(plan, "rotation", radians(v) || 0)), "degrees");
    }
    const help = element("p", { className: "help pad" });
    help.textContent = "Keys: V select · N node · E edge · S station · Z zone · F fit · Delete removes · Esc cancels · Ctrl+S saves. Drag empty space (or hold Space) to pan, wheel to zoom.";
    panel.append(help);
  }

  function renderNode(panel, node) {
    const grid = form(panel, "Node");
    field(grid, "Id", textInput(node.id, (v) => renameElement("nodes", node, v) || renderProperties()));
    field(grid, "x (m)", numberInput(node.x, (v) => numberOrNull(v) !== null && update(node, "x", Number(v))));
    field(grid, "y (m)", numberInput(node.y, (v) => numberOrNull(v) !== null && update(node, "y", Number(v))));
    field(grid, "θ (°)", numberInput(degrees(node.theta), (v) => update(node, "theta", radians(v))), "heading to hold here; empty: any");
    field(grid, "Name", textInput(node.name, (v) => update(node, "name", v)));
    const edges = [...model.edges.values()];
    const out = edges.filter((e) => e.start === node.id).length;
    const into = edges.filter((e) => e.end === node.id).length;
    field(grid, "Edges", element("span", {}, `${out} out, ${into} in`));
    const stationId = stationOfNode().get(node.id);
    const buttons = [];
    if (stationId) buttons.push(button(`Station ${stationId}`, () => select({ type: "station", id: stationId })));
    buttons.push(button("Delete node", deleteSelection, "button danger"));
    actions(panel, ...buttons);
  }

  function renderEdge(panel, edge) {
    const grid = form(panel, "Edge");
    const a = model.nodes.get(edge.start);
    const b = model.nodes.get(edge.end);
    field(grid, "Id", textInput(edge.id, (v) => renameElement("edges", edge, v) || renderProperties()));
    const ends = element("span", { className: "prop-links" });
    ends.append(button(edge.start, () => focusOn("node", edge.start), "link"), " → ", button(edge.end, () => focusOn("node", edge.end), "link"));
    field(grid, "From → to", ends);
    field(grid, "Length", element("span", {}, `${Math.hypot(b.x - a.x, b.y - a.y).toFixed(2)} m`));
    field(grid, "Max speed", numberInput(edge.maxSpeed, (v) => update(edge, "maxSpeed", numberOrNull(v)), { min: "0" }), "m/s for every vehicle; empty: none");
    field(grid, "Name", textInput(edge.name, (v) => update(edge, "name", v)));
    const reverseId = edgeOfPair().get(pairKey(edge.end, edge.start));
    field(grid, "Direction", element("span", {}, reverseId ? `two-way (reverse: ${reverseId})` : "one-way"));
    const buttons = [];
    if (reverseId) {
      buttons.push(button("Select reverse", () => select({ type: "edge", id: reverseId })));
      buttons.push(button("Make one-way", () => { model.edges.delete(reverseId); changed(); renderProperties(); }));
    } else {
      buttons.push(button("Make two-way", () => { addEdge(edge.end, edge.start); renderProperties(); }));
      buttons.push(button("Reverse", () => reverseEdge(edge)));
    }
    buttons.push(button("Delete edge", deleteSelection, "button danger"));
    actions(panel, ...buttons);
  }

  function reverseEdge(edge) {
    [edge.start, edge.end] = [edge.end, edge.start];
    changed();
    renderProperties();
  }

  function renderStation(panel, station) {
    const grid = form(panel, "Station");
    field(grid, "Id", textInput(station.id, (v) => renameElement("stations", station, v) || renderProperties()));
    field(grid, "Name", textInput(station.name, (v) => update(station, "name", v)));
    field(grid, "Kind", selectInput(DATA.choices.stationKinds, station.kind, (v) => update(station, "kind", v)));
    const nodes = element("span", { className: "prop-links" });
    station.nodes.forEach((nodeId, i) => {
      if (i) nodes.append(", ");
      nodes.append(button(nodeId, () => focusOn("node", nodeId), "link"));
    });
    field(grid, "Nodes", nodes, "where vehicles stop; the first is the primary one");
    actions(panel, button("Delete station", deleteSelection, "button danger"));
  }

  function renderZone(panel, zone) {
    const grid = form(panel, "Zone");
    field(grid, "Id", textInput(zone.id, (v) => renameElement("zones", zone, v) || renderProperties()));
    field(grid, "Name", textInput(zone.name, (v) => update(zone, "name", v)));
    field(grid, "Type", selectInput(DATA.choices.zoneTypes, zone.type, (v) => changeZoneType(zone, v)));
    const enabled = element("input", { type: "checkbox" });
    enabled.checked = zone.enabled;
    enabled.addEventListener("change", () => update(zone, "enabled", enabled.checked));
    field(grid, "Enabled", enabled, "a disabled zone does nothing");
    renderZoneRule(grid, zone);
    field(grid, "Corners", element("span", {}, `${zone.vertices.length} · ${polygonArea(zone.vertices).toFixed(1)} m²`), "drag the corner handles to reshape");
    field(grid, "Description", textInput(zone.description, (v) => update(zone, "description", v)));
    actions(panel, button("Delete zone", deleteSelection, "button danger"));
  }

  function renderZoneRule(grid, zone) {
    const type = zone.type;
    if (type === "SPEED_LIMIT") {
      field(grid, "Max speed", numberInput(zone.maxSpeed, (v) => update(zone, "maxSpeed", numberOrNull(v)), { min: "0" }), "m/s on every edge through the zone");
    }
    if (type === "DIRECTED" || type === "BIDIRECTED") {
      field(grid, "Direction (°)", numberInput(degrees(zone.direction), (v) => update(zone, "direction", radians(v))), "0 = +x (east), 90 = +y (north)");
      const choices = DATA.choices.limitations.filter(([value]) => type === "DIRECTED" || value !== "STRICT");
      field(grid, "Limitation", selectInput(choices, zone.limitation, (v) => update(zone, "limitation", v)));
    }
    if (type === "PENALTY") {
      field(grid, "Penalty", numberInput(zone.penaltyFactor, (v) => update(zone, "penaltyFactor", numberOrNull(v)), { min: "0", max: "1" }), "0 none … 1 only if nothing else");
    }
    if (type === "PRIORITY") {
      field(grid, "Priority", numberInput(zone.priorityFactor, (v) => update(zone, "priorityFactor", numberOrNull(v)), { min: "0", max: "1" }), "0 none … 1 strongly preferred");
    }
    if (type === "RELEASE") {
      field(grid, "On release loss", selectInput(DATA.choices.releaseLoss, zone.releaseLossBehavior, (v) => update(zone, "releaseLossBehavior", v)));
    }
    if (type === "RESTRICTED") {
      const note = `allowed vehicle types, comma separated (known: ${DATA.choices.vehicleTypes.join(", ") || "none"}); empty: closed to all`;
      field(grid, "Vehicle types", textInput(zone.vehicleTypes.join(", "), (v) => update(zone, "vehicleTypes", v.split(",").map((t) => t.trim()).filter(Boolean))), note);
    }
  }

  function changeZoneType(zone, type) {
    zone.type = type;
    for (const [key, value] of Object.entries(ZONE_DEFAULTS[type] || {})) {
      if (zone[key] === null || zone[key] === "" || zone[key] === undefined) zone[key] = value;
    }
    changed();
    renderProperties();
  }

  // ---------------------------------------------------------------- validate and save

  function buildPayload() {
    const payload = {
      baseRevision: ui.baseRevision,
      note: elements.note.value.trim(),
      floorPlan: model.floorPlan.url ? {
        scale: model.floorPlan.scale,
        originX: model.floorPlan.originX,
        originY: model.floorPlan.originY,
        rotation: model.floorPlan.rotation,
      } : null,
      nodes: [...model.nodes.values()].map((n) => ({ id: n.id, x: n.x, y: n.y, theta: n.theta, name: n.name })),
      edges: [...model.edges.values()].map((e) => ({ id: e.id, start: e.start, end: e.end, maxSpeed: e.maxSpeed, name: e.name })),
      stations: [...model.stations.values()].map((s) => ({ id: s.id, name: s.name, kind: s.kind, nodes: s.nodes })),
      zones: [...model.zones.values()].map((z) => ({ ...z })),
    };
    ui.payloadOrder = {
      nodes: payload.nodes.map((n) => n.id),
      edges: payload.edges.map((e) => e.id),
      stations: payload.stations.map((s) => s.id),
      zones: payload.zones.map((z) => z.id),
    };
    return payload;
  }

  async function postJson(url, payload) {
    const response = await fetch(url, {
      method: "POST",
      credentials: "same-origin",
      headers: { "Content-Type": "application/json", "X-CSRFToken": CSRF_TOKEN, Accept: "application/json" },
      body: JSON.stringify(payload),
    });
    let body = {};
    try {
      body = await response.json();
    } catch (error) {
      body = { detail: `the server answered ${response.status}` };
    }
    return { status: response.status, body };
  }

  async function validate() {
    if (ui.busy) return;
    ui.busy = true;
    setStatus("validating…", "busy");
    try {
      const { status, body } = await postJson(DATA.urls.check, buildPayload());
      if (status !== 200) throw new Error(body.detail || `the server answered ${status}`);
      showResults(body.problems, body.findings);
      setStatus(ui.dirty ? "unsaved changes (validated)" : "validated", ui.dirty ? "dirty" : "clean");
    } catch (error) {
      setStatus(`validation failed: ${error.message}`, "error");
    } finally {
      ui.busy = false;
    }
  }

  async function save() {
    if (ui.busy) return;
    ui.busy = true;
    setStatus("saving…", "busy");
    try {
      const { status, body } = await postJson(DATA.urls.save, buildPayload());
      if (status === 200) saved(body);
      else if (status === 422) {
        showResults(body.problems || [], []);
        setStatus(`not saved: ${(body.problems || []).length} problem(s)`, "error");
      } else setStatus(`not saved: ${body.detail || status}`, "error");
    } catch (error) {
      setStatus(`not saved: ${error.message}`, "error");
    } finally {
      ui.busy = false;
    }
  }

  function saved(body) {
    ui.baseRevision = body.revision;
    ui.version = body.version;
    ui.dirty = false;
    elements.note.value = "";
    document.getElementById("version-label").textContent = `version ${body.version}`;
    showResults([], body.findings);
    setStatus(`saved as version ${body.version}`, "saved");
    if (!ui.selection) renderProperties();
  }

  function showResults(problems, findings) {
    const list = elements.findings;
    list.replaceChildren();
    for (const problem of problems) list.append(problemItem(problem));
    for (const finding of findings) list.append(findingItem(finding));
    const errors = problems.length + findings.filter((f) => f.severity === "error").length;
    elements.findingsCount.textContent = String(problems.length + findings.length);
    elements.findingsCount.dataset.state = errors ? "error" : findings.length ? "warning" : "ok";
    if (!problems.length && !findings.length) {
      list.append(element("li", { className: "finding-empty" }, "No findings: every node and station can be reached and left."));
    }
  }

  function findingItem(finding) {
    const item = element("li", { className: `finding severity-${finding.severity}`, tabindex: "0" });
    item.append(
      element("span", { className: `badge severity-${finding.severity}` }, finding.severity),
      element("span", { className: "finding-object" }, `${finding.object_type} ${finding.object_id}`),
      element("span", { className: "finding-code" }, finding.code),
      element("span", { className: "finding-message" }, finding.message),
    );
    const focus = () => focusOn(finding.object_type, finding.object_id);
    item.addEventListener("click", focus);
    item.addEventListener("keydown", (event) => event.key === "Enter" && focus());
    return item;
  }

  function problemItem(problem) {
    const item = element("li", { className: "finding severity-error", tabindex: "0" });
    item.append(
      element("span", { className: "badge severity-error" }, "problem"),
      element("span", { className: "finding-object" }, problem.path),
      element("span", { className: "finding-message" }, problem.message),
    );
    const target = elementOfPath(problem.path);
    if (target) {
      const focus = () => focusOn(target.type, target.id);
      item.addEventListener("click", focus);
      item.addEventListener("keydown", (event) => event.key === "Enter" && focus());
    }
    return item;
  }

  function elementOfPath(path) {
    const match = /^\$\.(nodes|edges|stations|zones)\[(\d+)\]/.exec(path);
    if (!match || !ui.payloadOrder) return null;
    const id = ui.payloadOrder[match[1]][Number(match[2])];
    return id === undefined ? null : { type: match[1].slice(0, -1), id };
  }

  // ---------------------------------------------------------------- start

  function fillSelect(select, choices, selected) {
    for (const [value, text] of choices) {
      const option = element("option", { value }, text);
      if (value === selected) option.selected = true;
      select.append(option);
    }
  }

  function loadFloorPlan() {
    if (!model.floorPlan.url) return;
    floorPlanImage = new Image();
    floorPlanImage.addEventListener("load", requestDraw);
    floorPlanImage.src = model.floorPlan.url;
  }

  function findElements() {
    for (const [name, id] of Object.entries({
      wrap: "canvas-wrap", hint: "hint", status: "status", cursor: "cursor", counts: "counts",
      zoom: "zoom", properties: "properties", findings: "findings", findingsCount: "findings-count",
      twoWay: "two-way", stationKind: "station-kind", zoneType: "zone-type", snap: "snap", note: "note",
    })) {
      elements[name] = document.getElementById(id);
    }
  }

  function bindEvents() {
    canvas.addEventListener("pointerdown", onPointerDown);
    canvas.addEventListener("pointermove", onPointerMove);
    canvas.addEventListener("pointerup", onPointerUp);
    canvas.addEventListener("pointercancel", () => { ui.press = null; });
    canvas.addEventListener("pointerleave", () => { ui.pointer = null; ui.hover = null; requestDraw(); });
    canvas.addEventListener("wheel", onWheel, { passive: false });
    canvas.addEventListener("dblclick", onDoubleClick);
    canvas.addEventListener("contextmenu", (event) => event.preventDefault());
    document.addEventListener("keydown", onKeyDown);
    document.addEventListener("keyup", onKeyUp);
    for (const toolButton of document.querySelectorAll(".tool[data-tool]")) {
      toolButton.addEventListener("click", () => setTool(toolButton.dataset.tool));
    }
    document.getElementById("fit").addEventListener("click", () => fitView());
    document.getElementById("validate").addEventListener("click", validate);
    document.getElementById("save").addEventListener("click", save);
    new ResizeObserver(resizeCanvas).observe(elements.wrap);
    window.addEventListener("beforeunload", (event) => {
      if (ui.dirty) event.preventDefault();
    });
  }

  function start() {
    findElements();
    canvas = document.getElementById("editor-canvas");
    context = canvas.getContext("2d", { alpha: false }) || canvas.getContext("2d");
    fillSelect(elements.stationKind, DATA.choices.stationKinds, "PICK");
    fillSelect(elements.zoneType, DATA.choices.zoneTypes, "BLOCKED");
    loadModel();
    loadFloorPlan();
    bindEvents();
    resizeCanvas();
    fitView();
    setTool("select");
    renderProperties();
    setStatus(ui.version ? `version ${ui.version}, no changes` : "no changes", "clean");
    // For tests and the browser console: read the model, find nodes on screen.
    window.layoutEditor = { model, view, stats, ui, toScreen, focusOn, draw };
  }

  start();
})();
