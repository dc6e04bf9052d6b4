// The vehicles and orders tables beside the map.
//
// With 1,000 vehicles a table row per vehicle updated 5 times a second would cost more than the
// map, so the vehicles table is redrawn at most once a second and shows VEHICLE_ROWS rows: the
// selected vehicle first, then vehicles with errors, then by serial; the filter narrows them.

const VEHICLE_ROWS = 50;
const OPEN_ORDER_STATUSES = new Set(["NEW", "ASSIGNED", "IN_PROGRESS"]);
const COLUMNS = ["serial", "status", "battery", "mode", "last_node", "order", "waits", "errors"];

export function html(tag, className = "", text = "") {
  const element = document.createElement(tag);
  if (className) element.className = className;
  if (text) element.textContent = text;
  return element;
}

export function setText(element, text) {
  const value = text === null || text === undefined || text === "" ? "–" : String(text);
  if (element.textContent !== value) element.textContent = value;
}

export function fillBadge(cell, text, className) {
  let badge = cell.firstElementChild;
  if (!badge) badge = cell.appendChild(html("span"));
  badge.className = `badge ${className}`;
  setText(badge, text ? String(text).replace("_", " ").toLowerCase() : "");
}

// One collator: localeCompare with options builds a new one per call (slow with 1,000 rows).
const collator = new Intl.Collator(undefined, { numeric: true });
const bySerial = (a, b) => collator.compare(a.serial || "", b.serial || "");

export class VehicleTable {
  constructor({ onSelect }) {
    this.body = document.querySelector("#vehicles-table tbody");
    this.count = document.getElementById("vehicles-count");
    this.empty = document.getElementById("vehicles-empty");
    this.more = document.getElementById("vehicles-more");
    this.filter = document.getElementById("vehicles-filter");
    this.onSelect = onSelect;
    this.rows = []; // the <tr>s, reused
    this.filter?.addEventListener("input", () => this.render(this.lastVehicles, this.lastSelected));
  }

  // `vehicles`: Map key -> row; `selected`: the selected key or null.
  render(vehicles, selected) {
    this.lastVehicles = vehicles;
    this.lastSelected = selected;
    if (!vehicles) return;
    const needle = (this.filter?.value || "").trim().toLowerCase();
    const matching = [];
    for (const [key, row] of vehicles) {
      if (!needle || `${row.serial} ${row.manufacturer} ${row.status}`.toLowerCase().includes(needle)) {
        matching.push([key, row]);
      }
    }
    const rank = ([key, row]) => (key === selected ? 0 : (row.errors || []).length ? 1 : 2);
    matching.sort((a, b) => rank(a) - rank(b) || bySerial(a[1], b[1]));
    const shown = matching.slice(0, VEHICLE_ROWS);
    while (this.rows.length < shown.length) this.rows.push(this.createRow());
    shown.forEach(([key, row], i) => this.fillRow(this.rows[i], key, row, key === selected));
    const wanted = this.rows.slice(0, shown.length);
    if (this.body.children.length !== wanted.length || wanted.some((tr, i) => this.body.children[i] !== tr)) {
      this.body.replaceChildren(...wanted);
    }
    setText(this.count, String(vehicles.size));
    this.empty.hidden = vehicles.size > 0;
    if (this.more) {
      this.more.hidden = matching.length <= shown.length;
      setText(this.more, `${shown.length} of ${matching.length} shown (selected and with errors first); filter to find others`);
    }
  }

  createRow() {
    const tr = html("tr");
    for (const column of COLUMNS) tr.appendChild(html("td", `col-${column}`));
    tr.addEventListener("click", () => this.onSelect(tr.dataset.key));
    return tr;
  }

  fillRow(tr, key, row, selected) {
    tr.dataset.key = key;
    tr.dataset.id = row.id ?? "";
    tr.classList.toggle("selected", selected);
    tr.classList.toggle("offline", row.status === "offline");
    const cells = tr.children;
    setText(cells[0], row.serial);
    cells[0].title = `${row.manufacturer || ""} ${row.serial || ""}`.trim();
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
  }
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
  cell.querySelector(".battery-fill").style.width = `${percent.toFixed(0)}%`;
  cell.querySelector(".battery").classList.toggle("low", percent < 20);
  setText(cell.querySelector(".battery-value"), `${percent.toFixed(0)}%`);
}

export function renderOrders(orders) {
  const body = document.querySelector("#orders-table tbody");
  body.replaceChildren(...orders.map(orderRow));
  const open = orders.filter((order) => OPEN_ORDER_STATUSES.has(order.status)).length;
  setText(document.getElementById("orders-count"), String(open));
  document.getElementById("orders-empty").hidden = orders.length > 0;
}

function orderRow(order) {
  const tr = html("tr");
  tr.dataset.id = order.id;
  tr.appendChild(html("td", "col-id", `TO-${order.id}`));
  fillBadge(tr.appendChild(html("td", "col-status")), order.status, `order-${order.status}`);
  const path = tr.appendChild(html("td", "col-path"));
  path.append(html("span", "", order.source), html("span", "arrow", " → "), html("span", "", order.destination));
  tr.appendChild(html("td", "col-vehicle", order.vehicle || "–"));
  const reason = tr.appendChild(html("td", "col-reason", order.failure_reason || ""));
  reason.title = order.failure_reason || "";
  const time = (iso) => (iso ? new Date(iso).toLocaleString() : "");
  const created = `created ${time(order.created_at)}`;
  tr.title = order.finished_at ? `${created}, finished ${time(order.finished_at)}` : created;
  return tr;
}
