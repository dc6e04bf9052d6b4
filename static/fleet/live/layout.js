// The layout layer of the live map: zones, edges (one-way arrows), nodes, stations and their
// names, drawn onto the map's offscreen canvas in world coordinates (metres, y up) whenever the
// camera or the canvas size changes. `map` is the LiveMap (camera, px(), toScreen()).

const STATION_LABEL_MIN_SCALE = 9; // px per metre from which stations are named
const STATION_STYLE = {
  PICK: ["#d6ecff", "#2b87d8"],
  DROP: ["#f1e1fb", "#9b4fc9"],
  CHARGE: ["#fff1c9", "#d69a00"],
  PARK: ["#e8ebef", "#7d8896"],
};
const ZONE_STYLE = {
  BLOCKED: "#dc2626", RESTRICTED: "#dc2626", SPEED_LIMIT: "#f59e0b", DIRECTED: "#6366f1",
  BIDIRECTED: "#6366f1", PARKING: "#64748b", CHARGING: "#eab308", PENALTY: "#f97316",
  NO_STOPPING: "#f97316",
};

export function drawLayout(map, ctx) {
  drawZones(map, ctx);
  drawEdges(map, ctx);
  drawNodes(map, ctx);
  drawStations(map, ctx);
}

function drawZones(map, ctx) {
  ctx.lineWidth = map.px(1);
  ctx.setLineDash([map.px(4), map.px(3)]);
  for (const zone of map.layout.zones || []) {
    if (!zone.vertices.length) continue;
    const color = ZONE_STYLE[zone.type] || "#94a3b8";
    ctx.beginPath();
    zone.vertices.forEach(([x, y], i) => (i ? ctx.lineTo(x, y) : ctx.moveTo(x, y)));
    ctx.closePath();
    ctx.globalAlpha = 0.14;
    ctx.fillStyle = color;
    ctx.fill();
    ctx.globalAlpha = 0.7;
    ctx.strokeStyle = color;
    ctx.stroke();
  }
  ctx.globalAlpha = 1;
  ctx.setLineDash([]);
}

function drawEdges(map, ctx) {
  const directed = new Set(map.layout.edges.map((edge) => `${edge.start}>${edge.end}`));
  const drawn = new Set();
  const arrows = [];
  ctx.beginPath();
  for (const edge of map.layout.edges) {
    const start = map.nodes.get(edge.start);
    const end = map.nodes.get(edge.end);
    if (!start || !end) continue;
    const pair = edge.start < edge.end ? `${edge.start}|${edge.end}` : `${edge.end}|${edge.start}`;
    if (drawn.has(pair)) continue; // a two-way aisle is two edges: one line
    drawn.add(pair);
    ctx.moveTo(start.x, start.y);
    ctx.lineTo(end.x, end.y);
    if (!directed.has(`${edge.end}>${edge.start}`)) arrows.push([start, end]);
  }
  ctx.strokeStyle = "#aab6c4";
  ctx.lineWidth = Math.max(map.px(1), 0.07);
  ctx.lineCap = "butt";
  ctx.stroke();
  if (!arrows.length || map.camera.scale < 4) return;
  // One-way edges: an arrow head at the middle, pointing along the edge.
  const head = Math.max(map.px(5), 0.25);
  ctx.beginPath();
  for (const [start, end] of arrows) {
    const angle = Math.atan2(end.y - start.y, end.x - start.x);
    const mx = (start.x + end.x) / 2;
    const my = (start.y + end.y) / 2;
    ctx.moveTo(mx + head * Math.cos(angle), my + head * Math.sin(angle));
    ctx.lineTo(mx + head * Math.cos(angle + 2.5), my + head * Math.sin(angle + 2.5));
    ctx.lineTo(mx + head * Math.cos(angle - 2.5), my + head * Math.sin(angle - 2.5));
    ctx.closePath();
  }
  ctx.fillStyle = "#8896a8";
  ctx.fill();
}

function drawNodes(map, ctx) {
  const r = Math.max(map.px(1.5), 0.12);
  ctx.beginPath();
  for (const node of map.layout.nodes) {
    ctx.moveTo(node.x + r, node.y);
    ctx.arc(node.x, node.y, r, 0, 2 * Math.PI);
  }
  ctx.fillStyle = "#66768a";
  ctx.fill();
}

function drawStations(map, ctx) {
  const size = 0.9; // metres
  ctx.lineWidth = Math.max(map.px(1.5), 0.08);
  for (const [kind, [fill, stroke]] of Object.entries(STATION_STYLE)) {
    ctx.beginPath();
    for (const station of map.layout.stations) {
      if (station.kind === kind) ctx.rect(station.x - size / 2, station.y - size / 2, size, size);
    }
    ctx.fillStyle = fill;
    ctx.strokeStyle = stroke;
    ctx.fill();
    ctx.stroke();
  }
  if (map.camera.scale < STATION_LABEL_MIN_SCALE) return;
  map.screenTransform(ctx);
  ctx.font = `600 ${Math.min(13, Math.max(10, map.camera.scale * 0.42))}px ${map.font}`;
  ctx.textAlign = "center";
  ctx.textBaseline = "top";
  ctx.lineWidth = 3;
  ctx.strokeStyle = "#f8fafc";
  ctx.fillStyle = "#3c4757";
  for (const station of map.layout.stations) {
    const p = map.toScreen(station.x, station.y - size / 2);
    const text = station.name || station.id;
    ctx.strokeText(text, p.x, p.y + 3);
    ctx.fillText(text, p.x, p.y + 3);
  }
}
