"""A small ERP client for the rows that drive the REST API over real HTTP."""

import json
import urllib.error
import urllib.request
from typing import Any

ORDER_SCOPES = ("orders:read", "orders:write")


def issue_token(name: str) -> str:
    """An integration client allowed to create and read orders, and its bearer token."""
    from orders import services

    client = services.create_integration_client(name=name, scopes=ORDER_SCOPES)
    return services.issue_api_token(client=client)[1]


class Api:
    def __init__(self, port: int, token: str) -> None:
        self.base = f"http://127.0.0.1:{port}/api/v1"
        self.token = token

    def request(
        self,
        method: str,
        path: str,
        body: dict[str, Any] | None = None,
        key: str | None = None,
        timeout: float = 30.0,
    ) -> tuple[int, dict[str, Any], dict[str, str]]:
        """(status, JSON body, headers); status 0 when the connection itself failed."""
        headers = {"Authorization": f"Bearer {self.token}", "Content-Type": "application/json"}
        if key is not None:
            headers["Idempotency-Key"] = key
        data = json.dumps(body).encode() if body is not None else None
        request = urllib.request.Request(
            self.base + path, data=data, method=method, headers=headers
        )
        try:
            with urllib.request.urlopen(request, timeout=timeout) as response:  # noqa: S310
                return response.status, _json(response.read()), dict(response.headers)
        except urllib.error.HTTPError as error:
            return error.code, _json(error.read()), dict(error.headers)
        except (OSError, urllib.error.URLError):
            return 0, {}, {}

    def create_order(
        self, key: str | None, source: str, destination: str, ref: str
    ) -> tuple[int, dict[str, Any], dict[str, str]]:
        body = {"source": source, "destination": destination, "external_ref": ref}
        return self.request("POST", "/orders/", body, key)


def _json(raw: bytes) -> dict[str, Any]:
    try:
        value = json.loads(raw or b"{}")
    except ValueError:
        return {"raw": raw[:200].decode(errors="replace")}
    return value if isinstance(value, dict) else {"value": value}
