// The live map on a <canvas>: layout, vehicles, routes, reservations, waits; pan, zoom, pick.
//
// The layout (zones, edges, nodes, stations) is drawn once per camera change onto an offscreen
// canvas; every frame copies it and draws what moves on top, batched into one path per style
// (all bases, all horizons, all footprints of one status ...), so 1,000 vehicles cost one
// path per style and no DOM nodes. (Pre-drawn images per vehicle, copied with drawImage, were
// measured slower on a software canvas.) Frames are drawn only while something moves
// or changed.
//
// Coordinates: the layout is in metres with y up; the camera maps the world point (cx, cy) to
// the canvas centre at `scale` CSS pixels per metre, y flipped.

import { drawLayout } from "./layout.js";

const MARGIN = 2.5; // metres around the layout when fitting it
const MIN_SCALE = 1; // CSS px per metre
const MAX_SCALE = 400;
const SNAP_DISTANCE = 8; // metres: larger jumps are not animated
const MIN_TWEEN_MS = 80;
const MAX_TWEEN_MS = 1000;
const TWEEN_STRETCH = 1.15; // tweens last a bit longer than the gap between updates
const LABEL_MIN_SCALE = 14; // px per metre from which every vehicle is labelled
const LABEL_ALWAYS_BELOW = 60; // vehicles: few enough to label at any zoom
const OUTLINE_MIN_SCALE = 10; // px per metre from which footprints get a dark outline
const DASH_MIN_SCALE = 8; // px per metre from which horizons are dashed with many vehicles
const CLICK_SLOP_PX = 5; // a press that moved less than this is a click, not a drag
const PICK_PX = 6; // pixels of tolerance around a footprint when clicking
const DEFAULT_SIZE = [1.2, 0.8]; // length, width (metres): the planning default footprint
const ROUTE_STATUSES = new Set(["driving", "busy", "paused", "error"]);

export const STATUSES = ["idle", "driving", "busy", "charging", "paused", "error", "offline"];


export function vehicleKey(row) {
  return row.id === null || row.id === undefined ? `${row.manufacturer}/${row.serial}` : String(row.id);
}

function shortestTurn(from, to) {
  const turn = (to - from) % (2 * Math.PI);
  if (turn > Math.PI) return turn - 2 * Math.PI;
  if (turn < -Math.PI) return turn + 2 * Math.PI;
  return turn;
}

function interpolate(from, to, t) {
  return {
    x: from.x + (to.x - from.x) * t,
    y: from.y + (to.y - from.y) * t,
    theta: from.theta + shortestTurn(from.theta, to.theta) * t,
  };
}

function cssVar(name, fallback) {
  const value = getComputedStyle(document.documentElement).getPropertyValue(name).trim();
  return value || fallback;
}

export class LiveMap {
  constructor(canvas, layout, { onSelect = () => {} } = {}) {
    this.canvas = canvas;
    this.ctx = canvas.getContext("2d");
    this.layout = layout;
    this.onSelect = onSelect;
    this.nodes = new Map(layout.nodes.map((node) => [node.id, node]));
    this.sprites = new Map(); // vehicle key -> {row, pose, from, to, t0, duration, ...}
    this.bySerial = new Map(); // serial -> vehicle key (waits name vehicles by serial)
    this.selection = null; // {kind: "vehicle", key} or {kind: "station", id}
    this.layer = document.createElement("canvas");
    this.layerDirty = true;
    this.dirty = true;
    this.frame = 0;
    this.lastDrawEnd = 0;
    this.lastDrawCost = 0;
    this.width = 0;
    this.height = 0;
    this.dpr = 1;
    this.camera = { cx: 0, cy: 0, scale: 10 };
    this.fitted = false;
    this.stats = { frames: 0, drawMs: 0, since: performance.now() };
    this.colors = Object.fromEntries(
      STATUSES.map((status) => [status, cssVar(`--st-${status}`, "#66768a")]),
    );
    this.font = cssVar("--font", "sans-serif");
    this.resize();
    new ResizeObserver(() => this.resize()).observe(canvas.parentElement);
    this.bindInput();
  }

  // ------------------------------------------------------------ camera

  resize() {
    const box = this.canvas.parentElement.getBoundingClientRect();
    const dpr = window.devicePixelRatio || 1;
    const width = Math.max(1, Math.round(box.width));
    const height = Math.max(1, Math.round(box.height));
    if (width === this.width && height === this.height && dpr === this.dpr) return;
    Object.assign(this, { width, height, dpr });
    for (const canvas of [this.canvas, this.layer]) {
      canvas.width = Math.round(width * dpr);
      canvas.height = Math.round(height * dpr);
    }
    this.canvas.style.width = `${width}px`;
    this.canvas.style.height = `${height}px`;
    if (!this.fitted) this.fit();
    this.invalidateLayer();
  }

  bounds() {
    const xs = this.layout.nodes.map((node) => node.x);
    const ys = this.layout.nodes.map((node) => node.y);
    if (!xs.length) return { minX: -5, minY: -5, maxX: 5, maxY: 5 };
    return { minX: Math.min(...xs), maxX: Math.max(...xs), minY: Math.min(...ys), maxY: Math.max(...ys) };
  }

  fit() {
    const b = this.bounds();
    const spanX = b.maxX - b.minX + 2 * MARGIN;
    const spanY = b.maxY - b.minY + 2 * MARGIN;
    const scale = Math.min(this.width / spanX, this.height / spanY);
    this.camera = {
      cx: (b.minX + b.maxX) / 2,
      cy: (b.minY + b.maxY) / 2,
      scale: Math.min(MAX_SCALE, Math.max(MIN_SCALE, scale)),
    };
    this.fitted = true;
    this.invalidateLayer();
  }

  // Zoom by `factor` keeping the world point under (sx, sy) (CSS px in the canvas) in place.
  zoom(factor, sx = this.width / 2, sy = this.height / 2) {
    const before = this.toWorld(sx, sy);
    const scale = Math.min(MAX_SCALE, Math.max(MIN_SCALE, this.camera.scale * factor));
    this.camera.scale = scale;
    const after = this.toWorld(sx, sy);
    this.camera.cx += before.x - after.x;
    this.camera.cy += before.y - after.y;
    this.invalidateLayer();
  }

  pan(dx, dy) {
    this.camera.cx -= dx / this.camera.scale;
    this.camera.cy += dy / this.camera.scale;
    this.invalidateLayer();
  }

  toWorld(sx, sy) {
    const { cx, cy, scale } = this.camera;
    return { x: cx + (sx - this.width / 2) / scale, y: cy - (sy - this.height / 2) / scale };
  }

  toScreen(x, y) {
    const { cx, cy, scale } = this.camera;
    return { x: (x - cx) * scale + this.width / 2, y: (cy - y) * scale + this.height / 2 };
  }

  invalidateLayer() {
    this.layerDirty = true;
    this.requestDraw();
  }

  // ------------------------------------------------------------ input: drag, wheel, pinch, click

  bindInput() {
    const canvas = this.canvas;
    const pointers = new Map(); // pointerId -> {x, y}
    let press = null; // where a single-pointer press started, for click detection
    let pinch = 0; // distance between two pointers last time
    const local = (event) => {
      const box = canvas.getBoundingClientRect();
      return { x: event.clientX - box.left, y: event.clientY - box.top };
    };
    canvas.addEventListener("pointerdown", (event) => {
      canvas.setPointerCapture(event.pointerId);
      pointers.set(event.pointerId, local(event));
      press = pointers.size === 1 ? { ...local(event), moved: 0 } : null;
      pinch = 0;
    });
    canvas.addEventListener("pointermove", (event) => {
      const last = pointers.get(event.pointerId);
      if (!last) return;
      const point = local(event);
      pointers.set(event.pointerId, point);
      if (pointers.size === 1) {
        this.pan(point.x - last.x, point.y - last.y);
        if (press) press.moved += Math.hypot(point.x - last.x, point.y - last.y);
        canvas.classList.toggle("dragging", Boolean(press && press.moved > CLICK_SLOP_PX));
      } else if (pointers.size === 2) {
        const [a, b] = [...pointers.values()];
        const distance = Math.hypot(a.x - b.x, a.y - b.y);
        if (pinch) this.zoom(distance / pinch, (a.x + b.x) / 2, (a.y + b.y) / 2);
        pinch = distance;
      }
    });
    const release = (event) => {
      if (!pointers.delete(event.pointerId)) return;
      canvas.classList.remove("dragging");
      if (event.type === "pointerup" && press && press.moved <= CLICK_SLOP_PX) {
        this.select(this.pick(press.x, press.y));
      }
      press = null;
      pinch = 0;
    };
    canvas.addEventListener("pointerup", release);
    canvas.addEventListener("pointercancel", release);
    canvas.addEventListener("wheel", (event) => {
      event.preventDefault();
      const point = local(event);
      const lines = event.deltaMode === 1 ? 33 : 1; // Firefox scrolls by lines
      this.zoom(Math.exp(-event.deltaY * lines * 0.0015), point.x, point.y);
    }, { passive: false });
  }

  // What is under (sx, sy): the nearest vehicle whose footprint covers it, else a station.
  pick(sx, sy) {
    const world = this.toWorld(sx, sy);
    const slack = PICK_PX / this.camera.scale;
    let best = null;
    let bestDistance = Infinity;
    for (const [key, sprite] of this.sprites) {
      const pose = sprite.pose;
      if (!pose) continue;
      const dx = world.x - pose.x;
      const dy = world.y - pose.y;
      const cos = Math.cos(pose.theta);
      const sin = Math.sin(pose.theta);
      const along = dx * cos + dy * sin;
      const across = -dx * sin + dy * cos;
      const [length, width] = sprite.size;
      if (Math.abs(along) <= length / 2 + slack && Math.abs(across) <= width / 2 + slack) {
        const distance = Math.hypot(dx, dy);
        if (distance < bestDistance) [best, bestDistance] = [key, distance];
      }
    }
    if (best !== null) return { kind: "vehicle", key: best };
    const reach = 0.45 + slack;
    for (const station of this.layout.stations) {
      if (Math.abs(world.x - station.x) <= reach && Math.abs(world.y - station.y) <= reach) {
        return { kind: "station", id: station.id };
      }
    }
    return null;
  }

  select(selection) {
    this.selection = selection;
    this.requestDraw();
    this.onSelect(selection);
  }

  // ------------------------------------------------------------ vehicles

  setVehicle(row, now) {
    const key = vehicleKey(row);
    let sprite = this.sprites.get(key);
    if (!sprite) {
      sprite = { row, pose: null, from: null, to: null, t0: 0, duration: 0, lastUpdate: 0, interval: 0 };
      this.sprites.set(key, sprite);
    }
    sprite.row = row;
    sprite.size = Array.isArray(row.size) && row.size[0] > 0 && row.size[1] > 0 ? row.size : DEFAULT_SIZE;
    if (row.serial) this.bySerial.set(row.serial, key);
    const visible = Number.isFinite(row.x) && Number.isFinite(row.y)
      && (!row.map || row.map === this.layout.mapId);
    if (!visible) {
      Object.assign(sprite, { pose: null, from: null, to: null });
    } else {
      const theta = Number.isFinite(row.theta) ? row.theta : (sprite.to ? sprite.to.theta : 0);
      this.setTarget(sprite, { x: row.x, y: row.y, theta }, now);
    }
    this.requestDraw();
  }

  removeVehicle(key) {
    const sprite = this.sprites.get(key);
    if (!sprite) return;
    if (this.bySerial.get(sprite.row.serial) === key) this.bySerial.delete(sprite.row.serial);
    this.sprites.delete(key);
    if (this.selection && this.selection.kind === "vehicle" && this.selection.key === key) this.select(null);
    this.requestDraw();
  }

  // Tween from where the vehicle is drawn now to `target` over about the gap between the last
  // two updates (smoothed, stretched a little), so motion stays continuous at ~5 updates/s.
  setTarget(sprite, target, now) {
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
    if (!from) sprite.pose = target;
  }

  // Advance every sprite to time `now`; true while any is still moving.
  animate(now) {
    let moving = false;
    for (const sprite of this.sprites.values()) {
      if (!sprite.to) continue;
      const tweening = sprite.duration > 0 && sprite.from;
      const progress = tweening ? Math.min(1, (now - sprite.t0) / sprite.duration) : 1;
      sprite.pose = progress >= 1 ? sprite.to : interpolate(sprite.from, sprite.to, progress);
      if (progress < 1) moving = true;
    }
    return moving;
  }

  // ------------------------------------------------------------ frames

  requestDraw() {
    this.dirty = true;
    if (!this.frame) this.frame = requestAnimationFrame((now) => this.draw(now));
  }

  draw(now) {
    this.frame = 0;
    // On a slow machine (software canvas, a busy core) drawing may take longer than a frame:
    // keep it to about two thirds of the main thread so websocket messages are still taken in.
    if (now - this.lastDrawEnd < this.lastDrawCost / 2) {
      this.requestDraw();
      return;
    }
    const started = performance.now();
    const moving = this.animate(now);
    if (this.layerDirty) this.drawLayer();
    const ctx = this.ctx;
    ctx.setTransform(1, 0, 0, 1, 0, 0);
    ctx.clearRect(0, 0, this.canvas.width, this.canvas.height);
    ctx.drawImage(this.layer, 0, 0);
    this.worldTransform(ctx);
    const visible = this.visibleSprites();
    this.drawReservations(ctx, visible);
    this.drawRoutes(ctx, visible);
    this.drawWaits(ctx, visible);
    this.drawVehicles(ctx, visible);
    this.drawSelection(ctx);
    this.drawVehicleLabels(ctx, visible);
    this.dirty = false;
    const ended = performance.now();
    this.lastDrawCost = ended - started;
    this.lastDrawEnd = ended;
    this.stats.frames += 1;
    this.stats.drawMs += this.lastDrawCost;
    if (moving) this.requestDraw();
  }

  worldTransform(ctx) {
    const { cx, cy, scale } = this.camera;
    const k = this.dpr * scale;
    ctx.setTransform(k, 0, 0, -k, this.dpr * (this.width / 2 - cx * scale), this.dpr * (this.height / 2 + cy * scale));
  }

  screenTransform(ctx) {
    ctx.setTransform(this.dpr, 0, 0, this.dpr, 0, 0);
  }

  px(pixels) {
    return pixels / this.camera.scale; // a length of `pixels` CSS px in metres
  }

  visibleSprites() {
    const low = this.toWorld(0, this.height);
    const high = this.toWorld(this.width, 0);
    const pad = 3;
    const visible = [];
    for (const [key, sprite] of this.sprites) {
      const pose = sprite.pose;
      if (!pose) continue;
      const onScreen = pose.x > low.x - pad && pose.x < high.x + pad && pose.y > low.y - pad && pose.y < high.y + pad;
      // Routes of off-screen vehicles may still cross the view: keep vehicles with a route.
      if (onScreen || (sprite.row.base || []).length || (sprite.row.horizon || []).length) {
        visible.push([key, sprite, onScreen]);
      }
    }
    return visible;
  }

  // ---- the layout layer (redrawn only when the camera or the canvas size changes)

  drawLayer() {
    this.layerDirty = false;
    const ctx = this.layer.getContext("2d");
    ctx.setTransform(1, 0, 0, 1, 0, 0);
    ctx.clearRect(0, 0, this.layer.width, this.layer.height);
    this.worldTransform(ctx);
    drawLayout(this, ctx);
  }

  // ---- what moves

  drawReservations(ctx, visible) {
    const r = 0.45;
    ctx.beginPath();
    for (const [, sprite] of visible) {
      for (const [x, y] of sprite.row.reserved || []) {
        ctx.moveTo(x + r, y);
        ctx.arc(x, y, r, 0, 2 * Math.PI);
      }
    }
    ctx.fillStyle = "rgba(47, 111, 222, 0.12)";
    ctx.fill();
  }

  // The remaining route starts at the vehicle; the horizon continues where the base ends.
  routePaths(sprite) {
    const { base = [], horizon = [] } = sprite.row;
    if (!ROUTE_STATUSES.has(sprite.row.status) && !base.length && !horizon.length) return null;
    const start = [sprite.pose.x, sprite.pose.y];
    const basePoints = base.length ? [start, ...base] : [];
    const horizonStart = basePoints.length ? basePoints[basePoints.length - 1] : start;
    return { base: basePoints, horizon: horizon.length ? [horizonStart, ...horizon] : [] };
  }

  drawRoutes(ctx, visible) {
    const bases = new Path2D();
    const horizons = new Path2D();
    for (const [, sprite] of visible) {
      const paths = this.routePaths(sprite);
      if (!paths) continue;
      addPolyline(bases, paths.base);
      addPolyline(horizons, paths.horizon);
    }
    // Butt caps and mitre joins: round ones cost several times more on a software canvas.
    ctx.lineCap = "butt";
    ctx.lineJoin = "miter";
    ctx.strokeStyle = "rgba(47, 111, 222, 0.7)";
    ctx.lineWidth = Math.max(this.px(2), 0.16);
    ctx.stroke(bases);
    ctx.strokeStyle = "rgba(47, 111, 222, 0.55)";
    ctx.lineWidth = Math.max(this.px(1.5), 0.1);
    // Dashing a thousand horizons costs more than everything else drawn per frame; zoomed out
    // (a vehicle under ~10 px) they are told apart from bases by being thin and light instead.
    const dashed = this.camera.scale >= DASH_MIN_SCALE || this.sprites.size <= LABEL_ALWAYS_BELOW;
    if (dashed) ctx.setLineDash([Math.max(this.px(6), 0.35), Math.max(this.px(4), 0.25)]);
    ctx.stroke(horizons);
    ctx.setLineDash([]);
  }

  // A waiting vehicle points at each vehicle it waits for (both where they are drawn now).
  drawWaits(ctx, visible) {
    ctx.beginPath();
    let any = false;
    for (const [, sprite] of visible) {
      for (const serial of sprite.row.waiting_for || []) {
        const other = this.sprites.get(this.bySerial.get(serial));
        if (!other || !other.pose) continue;
        ctx.moveTo(sprite.pose.x, sprite.pose.y);
        ctx.lineTo(other.pose.x, other.pose.y);
        any = true;
      }
    }
    if (!any) return;
    ctx.strokeStyle = "#c2410c";
    ctx.lineWidth = Math.max(this.px(1.5), 0.08);
    ctx.setLineDash([Math.max(this.px(4), 0.2), Math.max(this.px(3), 0.2)]);
    ctx.stroke();
    ctx.setLineDash([]);
  }

  // Footprints (length × width, pointed at the front) rotated by heading, one path per status
  // (one fill each), outlined only when big enough to show it; loads and error rings batched.
  drawVehicles(ctx, visible) {
    const byStatus = new Map();
    const loads = new Path2D();
    const errors = new Path2D();
    for (const [, sprite, onScreen] of visible) {
      if (!onScreen) continue;
      const status = this.colors[sprite.row.status] ? sprite.row.status : "offline";
      let path = byStatus.get(status);
      if (!path) byStatus.set(status, (path = new Path2D()));
      addFootprint(path, sprite.pose, sprite.size);
      if (sprite.row.loaded) addSquare(loads, sprite.pose, Math.min(sprite.size[0], sprite.size[1]) * 0.45);
      if (status === "error") addCircle(errors, sprite.pose, Math.max(...sprite.size) * 0.75);
    }
    const outline = this.camera.scale >= OUTLINE_MIN_SCALE;
    ctx.strokeStyle = "#101820";
    ctx.lineWidth = Math.min(this.px(1), 0.05);
    for (const [status, path] of byStatus) {
      ctx.fillStyle = this.colors[status];
      ctx.globalAlpha = status === "offline" ? 0.7 : 1;
      ctx.fill(path);
      if (outline) ctx.stroke(path);
    }
    ctx.globalAlpha = 1;
    ctx.fillStyle = "#8b5a2b";
    ctx.fill(loads);
    ctx.strokeStyle = this.colors.error;
    ctx.lineWidth = Math.max(this.px(1.5), 0.08);
    ctx.setLineDash([Math.max(this.px(4), 0.2), Math.max(this.px(3), 0.15)]);
    ctx.stroke(errors);
    ctx.setLineDash([]);
  }

  drawSelection(ctx) {
    const selection = this.selection;
    if (!selection) return;
    ctx.strokeStyle = "#101820";
    ctx.lineWidth = Math.max(this.px(2), 0.08);
    if (selection.kind === "vehicle") {
      const sprite = this.sprites.get(selection.key);
      if (!sprite || !sprite.pose) return;
      const paths = this.routePaths(sprite);
      if (paths) {
        const route = new Path2D();
        addPolyline(route, paths.base);
        addPolyline(route, paths.horizon);
        ctx.strokeStyle = "#0b2f73";
        ctx.stroke(route);
        ctx.strokeStyle = "#101820";
      }
      const ring = new Path2D();
      addCircle(ring, sprite.pose, Math.max(...sprite.size) * 0.8 + this.px(2));
      ctx.stroke(ring);
    } else {
      const station = this.layout.stations.find((s) => s.id === selection.id);
      if (!station) return;
      ctx.strokeRect(station.x - 0.65, station.y - 0.65, 1.3, 1.3);
    }
  }

  drawVehicleLabels(ctx, visible) {
    const many = this.sprites.size > LABEL_ALWAYS_BELOW;
    if (many && this.camera.scale < LABEL_MIN_SCALE) return;
    this.screenTransform(ctx);
    ctx.font = `700 ${Math.min(13, Math.max(10, this.camera.scale * 0.45))}px ${this.font}`;
    ctx.textAlign = "center";
    ctx.textBaseline = "bottom";
    ctx.lineWidth = 3;
    ctx.lineJoin = "round";
    ctx.strokeStyle = "#ffffff";
    ctx.fillStyle = "#101820";
    for (const [, sprite, onScreen] of visible) {
      if (!onScreen || !sprite.row.serial) continue;
      const p = this.toScreen(sprite.pose.x, sprite.pose.y);
      const lift = Math.max(...sprite.size) * 0.5 * this.camera.scale + 4;
      ctx.strokeText(sprite.row.serial, p.x, p.y - lift);
      ctx.fillText(sprite.row.serial, p.x, p.y - lift);
    }
  }
}

function addPolyline(path, points) {
  if (points.length < 2) return;
  path.moveTo(points[0][0], points[0][1]);
  for (let i = 1; i < points.length; i += 1) path.lineTo(points[i][0], points[i][1]);
}

function addCircle(path, pose, r) {
  path.moveTo(pose.x + r, pose.y);
  path.arc(pose.x, pose.y, r, 0, 2 * Math.PI);
}

function addSquare(path, pose, side) {
  path.rect(pose.x - side / 2, pose.y - side / 2, side, side);
}

// The footprint at `pose`: a rectangle whose front corners are cut to show the heading.
function addFootprint(path, pose, [length, width]) {
  const cos = Math.cos(pose.theta);
  const sin = Math.sin(pose.theta);
  const half = length / 2;
  const side = width / 2;
  const shoulder = half - Math.min(side, half) * 0.6;
  const x = (a, b) => pose.x + a * cos - b * sin;
  const y = (a, b) => pose.y + a * sin + b * cos;
  path.moveTo(x(-half, -side), y(-half, -side));
  path.lineTo(x(shoulder, -side), y(shoulder, -side));
  path.lineTo(x(half, 0), y(half, 0));
  path.lineTo(x(shoulder, side), y(shoulder, side));
  path.lineTo(x(-half, side), y(-half, side));
  path.closePath();
}
