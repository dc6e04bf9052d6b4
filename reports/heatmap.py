"""The wait heatmap as inline SVG: the layout's edges and nodes in grey, and a disc on every node
where vehicles waited, its area and colour growing with the wait seconds there. Server-side,
like reports.charts, so the page needs no script and the SVG scales with the browser."""

import math
from html import escape

from reports.wait_selectors import WaitHeatmap

SIZE = 1000.0
MARGIN = 30.0
# From pale yellow (little waiting) to dark red (the node with the most wait seconds).
COLD, HOT = (255, 214, 102), (178, 24, 43)


def colour(share: float) -> str:
    r, g, b = (round(c + (h - c) * share) for c, h in zip(COLD, HOT, strict=True))
    return f"#{r:02x}{g:02x}{b:02x}"


def heatmap_svg(heatmap: WaitHeatmap, label: str) -> str:
    """SVG markup (every text escaped); layout y points up, SVG y down, so y is flipped."""
    points = heatmap.nodes or [(h.x, h.y) for h in heatmap.heat]
    xs, ys = [p[0] for p in points], [p[1] for p in points]
    left, right, bottom, top = min(xs), max(xs), min(ys), max(ys)
    span = max(right - left, top - bottom, 1e-6)
    scale = (SIZE - 2 * MARGIN) / span
    width = (right - left) * scale + 2 * MARGIN
    height = (top - bottom) * scale + 2 * MARGIN

    def at(x: float, y: float) -> tuple[float, float]:
        return MARGIN + (x - left) * scale, MARGIN + (top - y) * scale

    parts = [
        f'<svg class="heatmap" viewBox="0 0 {width:.0f} {height:.0f}" role="img" '
        f'aria-label="{escape(label)}" data-map="{escape(heatmap.map_id)}">',
        '<g class="heatmap-layout">',
    ]
    for x1, y1, x2, y2 in heatmap.edges:
        (a, b), (c, d) = at(x1, y1), at(x2, y2)
        parts.append(f'<line x1="{a:.1f}" y1="{b:.1f}" x2="{c:.1f}" y2="{d:.1f}"/>')
    for x, y in heatmap.nodes:
        a, b = at(x, y)
        parts.append(f'<circle cx="{a:.1f}" cy="{b:.1f}" r="2.5"/>')
    parts.append('</g><g class="heatmap-heat">')
    most = max((h.seconds for h in heatmap.heat), default=0.0) or 1.0
    for heat in sorted(heatmap.heat, key=lambda h: h.seconds):
        share = heat.seconds / most
        a, b = at(heat.x, heat.y)
        radius = 6 + 24 * math.sqrt(share)
        title = f"{heat.node_id}: {heat.seconds:.0f} s waited in {heat.count} waits"
        parts.append(
            f'<circle class="heat" data-node="{escape(heat.node_id)}" '
            f'data-seconds="{heat.seconds:.0f}" cx="{a:.1f}" cy="{b:.1f}" r="{radius:.1f}" '
            f'fill="{colour(share)}"><title>{escape(title)}</title></circle>'
        )
    parts.append("</g></svg>")
    return "".join(parts)
