"""Chart geometry for the report pages: the templates draw it as inline SVG (no chart library).

Pure functions from numbers to rectangles in a fixed viewBox, so the browser scales the chart and
nothing has to be loaded from anywhere.
"""

from collections.abc import Sequence
from dataclasses import dataclass
from html import escape

WIDTH = 1000.0
HEIGHT = 220.0
AXIS = 36.0  # room on the left for the axis labels
TOP = 10.0  # room above the highest bar for the top axis label


@dataclass(frozen=True)
class Rect:
    x: float
    y: float
    width: float
    height: float
    title: str
    part: str = ""


@dataclass(frozen=True)
class Tick:
    y: float
    label: str


@dataclass(frozen=True)
class Chart:
    width: float
    height: float
    rects: list[Rect]
    ticks: list[Tick]
    labels: list[tuple[float, str]]  # x position, text (thinned out to stay readable)

    @property
    def view_box(self) -> str:
        return f"0 0 {self.width:g} {self.height + 20:g}"

    def svg(self, label: str) -> str:
        """The chart as inline SVG markup (every text escaped), drawn in one pass."""
        parts = [
            f'<svg class="chart" viewBox="{self.view_box}" role="img" '
            f'aria-label="{escape(label)}" preserveAspectRatio="none">'
        ]
        for tick in self.ticks:
            parts.append(
                f'<line class="chart-grid" x1="{AXIS:g}" x2="{self.width:g}" y1="{tick.y:.1f}" '
                f'y2="{tick.y:.1f}"/><text class="chart-tick" x="{AXIS - 4:g}" y="{tick.y:.1f}" '
                f'dy="4" text-anchor="end">{escape(tick.label)}</text>'
            )
        for r in self.rects:
            parts.append(
                f'<rect class="bar bar-{escape(r.part)}" x="{r.x:.2f}" y="{r.y:.2f}" '
                f'width="{r.width:.2f}" height="{r.height:.2f}">'
                f"<title>{escape(r.title)}</title></rect>"
            )
        for x, text in self.labels:
            parts.append(
                f'<text class="chart-label" x="{x:.1f}" y="{self.height + 14:g}" '
                f'text-anchor="middle">{escape(text)}</text>'
            )
        parts.append("</svg>")
        return "".join(parts)


def nice_maximum(value: float) -> float:
    """The smallest 1/2/5 × 10ⁿ at or above `value` (an axis maximum that reads well)."""
    if value <= 0:
        return 1.0
    scale = 1.0
    while scale * 10 <= value:
        scale *= 10
    while scale > value:
        scale /= 10
    return next(step * scale for step in (1, 2, 5, 10) if step * scale >= value)


def stacked_columns(
    columns: Sequence[dict[str, float]],
    labels: Sequence[str],
    parts: Sequence[str],
    *,
    max_labels: int = 12,
    top: float | None = None,
) -> Chart:
    """Vertical columns, each a stack of `parts` (bottom first), one per label; `top` fixes the
    axis maximum (100 for shares), else it is the next round number above the highest column."""
    highest = max((sum(c.get(p, 0.0) for p in parts) for c in columns), default=0.0)
    top = top or nice_maximum(highest)
    plot = HEIGHT - TOP
    slot = (WIDTH - AXIS) / max(len(columns), 1)
    rects = []
    for index, (column, label) in enumerate(zip(columns, labels, strict=True)):
        base = HEIGHT
        for part in parts:
            value = column.get(part, 0.0)
            if value <= 0:
                continue
            height = min(value / top * plot, base - TOP)  # a stack never leaves the plot
            base -= height
            title = f"{label}: {value:g} {part}"
            left = AXIS + index * slot + slot * 0.1
            rects.append(Rect(left, base, slot * 0.8, height, title, part))
    step = max(1, -(-len(labels) // max_labels))
    names = [(AXIS + (i + 0.5) * slot, label) for i, label in enumerate(labels) if i % step == 0]
    ticks = [Tick(HEIGHT - plot * share, f"{top * share:g}") for share in (0, 0.5, 1)]
    return Chart(WIDTH, HEIGHT, rects, ticks, names)


def columns(values: Sequence[float], labels: Sequence[str], *, part: str = "value") -> Chart:
    """Plain vertical columns."""
    return stacked_columns([{part: v} for v in values], labels, [part])
