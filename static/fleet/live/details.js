// The details panel over the map: what was clicked, a vehicle or a station.

import { fillBadge, html, setText } from "./tables.js";

function vehiclePageUrl(row) {
  return `/vehicles/${encodeURIComponent(row.manufacturer)}/${encodeURIComponent(row.serial)}/`;
}

function fmt(value, digits = 2) {
  return Number.isFinite(value) ? value.toFixed(digits) : "";
}

export class DetailsPanel {
  constructor({ onClose }) {
    this.panel = document.getElementById("map-details");
    this.title = this.panel.querySelector(".details-title");
    this.badge = this.panel.querySelector(".details-badge");
    this.list = this.panel.querySelector(".details-list");
    this.link = this.panel.querySelector(".details-link");
    this.panel.querySelector(".details-close").addEventListener("click", onClose);
  }

  hide() {
    this.panel.hidden = true;
    delete this.panel.dataset.kind;
    delete this.panel.dataset.key;
  }

  showVehicle(key, row) {
    this.panel.hidden = false;
    this.panel.dataset.kind = "vehicle";
    this.panel.dataset.key = key;
    setText(this.title, row.serial);
    this.badge.hidden = false;
    fillBadge(this.badge, row.status, `status-${row.status}`);
    const actions = (row.instant_actions || []).map((a) => `${a.type} ${a.status.toLowerCase()}`);
    this.fill([
      ["Manufacturer", row.manufacturer],
      ["Connection", row.connection ? String(row.connection).toLowerCase() : ""],
      ["Mode", row.mode ? String(row.mode).toLowerCase() : ""],
      ["Battery", Number.isFinite(row.battery) ? `${row.battery.toFixed(0)} %` : ""],
      ["Loaded", row.loaded ? "yes" : "no"],
      ["Order", row.transport_order ? `TO-${row.transport_order} (${row.order})` : row.order],
      ["Last node", row.last_node],
      ["Position", Number.isFinite(row.x) ? `${fmt(row.x)}, ${fmt(row.y)} m · ${fmt((row.theta || 0) * 180 / Math.PI, 0)}°` : ""],
      ["Route", `${(row.base || []).length} base, ${(row.horizon || []).length} horizon nodes`],
      ["Reserved", (row.reserved || []).length ? `${row.reserved.length} nodes` : ""],
      ["Waits for", (row.waiting_for || []).join(", ")],
      ["Errors", (row.errors || []).join("; ")],
      ["Instant actions", actions.join("; ")],
    ]);
    this.link.hidden = !(row.manufacturer && row.serial);
    this.link.href = vehiclePageUrl(row);
    setText(this.link, "Vehicle page →");
  }

  showStation(station, vehiclesHere) {
    this.panel.hidden = false;
    this.panel.dataset.kind = "station";
    this.panel.dataset.key = station.id;
    setText(this.title, station.name || station.id);
    this.badge.hidden = false;
    fillBadge(this.badge, station.kind, `kind-${station.kind}`);
    this.fill([
      ["Station", station.id],
      ["Kind", String(station.kind).toLowerCase()],
      ["Node", station.node],
      ["Position", `${fmt(station.x)}, ${fmt(station.y)} m`],
      ["Vehicles here", vehiclesHere.join(", ")],
    ]);
    this.link.hidden = true;
  }

  fill(pairs) {
    const items = [];
    for (const [label, value] of pairs) {
      items.push(html("dt", "", label));
      const dd = html("dd");
      setText(dd, value);
      items.push(dd);
    }
    this.list.replaceChildren(...items);
  }
}
