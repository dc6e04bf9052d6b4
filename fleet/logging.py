"""Structured logs: one JSON object per line when LOG_FORMAT=json (fleet.settings.LOGGING).

Every line has `time` (UTC, ISO 8601), `level`, `logger`, `message`, `process` and `thread`;
`exception` with the traceback when there is one; and any `extra={...}` fields given to the
logging call, so a collector (Loki, Elasticsearch, journald) can filter on them.
"""

import json
import logging
from datetime import UTC, datetime
from typing import Any

# Attributes every LogRecord has: anything else came from `extra=`.
_STANDARD = set(vars(logging.makeLogRecord({}))) | {"message", "asctime", "taskName"}


class JsonFormatter(logging.Formatter):
    """Formats a record as a single JSON line."""

    def format(self, record: logging.LogRecord) -> str:
        data: dict[str, Any] = {
            "time": datetime.fromtimestamp(record.created, UTC).isoformat(timespec="milliseconds"),
            "level": record.levelname,
            "logger": record.name,
            "message": record.getMessage(),
            "process": record.process,
            "thread": record.threadName,
        }
        if record.exc_info:
            data["exception"] = self.formatException(record.exc_info)
        if record.stack_info:
            data["stack"] = self.formatStack(record.stack_info)
        for key, value in vars(record).items():
            if key not in _STANDARD and key not in data:
                data[key] = value
        return json.dumps(data, default=str, ensure_ascii=False)
