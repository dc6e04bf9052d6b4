"""What an import found: problems with their JSON path, and what it created."""

from dataclasses import dataclass, field
from typing import Any, Literal

Severity = Literal["error", "warning"]


@dataclass(frozen=True)
class Problem:
    """One finding of the importer at a JSON path, e.g. `$.layouts[0].edges[3].startNodeId`."""

    path: str
    message: str
    severity: Severity = "error"

    def __str__(self) -> str:
        return f"{self.path}: {self.message}"


@dataclass
class ImportReport:
    """The outcome of one LIF import. With any error, nothing was written."""

    site: str = ""
    project: str = ""
    errors: list[Problem] = field(default_factory=list)
    warnings: list[Problem] = field(default_factory=list)
    prefix: str = ""
    maps: list[str] = field(default_factory=list)
    counts: dict[str, int] = field(default_factory=dict)
    import_pk: int | None = None

    @property
    def ok(self) -> bool:
        return not self.errors

    def error(self, path: str, message: str) -> None:
        self.errors.append(Problem(path, message, "error"))

    def warn(self, path: str, message: str) -> None:
        self.warnings.append(Problem(path, message, "warning"))

    def as_dict(self) -> dict[str, Any]:
        """Plain data for the API, the admin and the stored LifImport row."""
        return {
            "ok": self.ok,
            "site": self.site,
            "project": self.project,
            "prefix": self.prefix,
            "maps": list(self.maps),
            "counts": dict(self.counts),
            "errors": [str(p) for p in self.errors],
            "warnings": [str(p) for p in self.warnings],
        }

    def lines(self) -> list[str]:
        """Readable lines for the command line."""
        head = "imported" if self.ok else "not imported"
        counts = ", ".join(f"{n} {what}" for what, n in self.counts.items())
        lines = [f"{head}: {self.project or '?'} into site {self.site or '?'}"]
        if self.ok:
            lines.append(f"maps {', '.join(self.maps) or '-'}; {counts}")
        lines += [f"error: {p}" for p in self.errors]
        lines += [f"warning: {p}" for p in self.warnings]
        return lines
