// Live alert banner: polls /alerts/banner.json (served by the app) and shows open alerts.
(function () {
  "use strict";
  const banner = document.getElementById("alert-banner");
  if (!banner) return;
  const url = banner.dataset.feed;
  const order = ["FATAL", "CRITICAL", "URGENT", "WARNING", "INFO"];

  function render(data) {
    if (!data.open) {
      banner.hidden = true;
      return;
    }
    const worst = order.find((s) => data.by_severity[s]) || "INFO";
    banner.className = "alert-banner alert-" + worst.toLowerCase();
    const top = data.top[0];
    const text = banner.querySelector(".alert-banner-text");
    text.textContent =
      data.open + " open alert" + (data.open === 1 ? "" : "s") +
      " (" + data.unacknowledged + " unacknowledged)" +
      (top ? " · " + top.severity + ": " + top.message : "");
    banner.hidden = false;
  }

  function poll() {
    fetch(url, { credentials: "same-origin", headers: { Accept: "application/json" } })
      .then((r) => (r.ok ? r.json() : null))
      .then((data) => data && render(data))
      .catch(() => {})
      .finally(() => setTimeout(poll, 5000));
  }
  poll();
})();
