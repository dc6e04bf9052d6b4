"""Signatures of webhook bodies: HMAC-SHA256 over the timestamp and the raw body.

The header reads `X-Fleet-Signature: t=<unix seconds>,v1=<hex digest>`, where the digest is
HMAC-SHA256 with the subscription's secret over `<t>.` followed by the exact body bytes. A
receiver recomputes it, compares in constant time and rejects old timestamps (replays).
"""

import hashlib
import hmac
import time

SIGNATURE_HEADER = "X-Fleet-Signature"


def sign(secret: str, body: bytes, timestamp: int) -> str:
    """The signature header value for `body` sent at `timestamp`."""
    digest = hmac.new(secret.encode(), f"{timestamp}.".encode() + body, hashlib.sha256)
    return f"t={timestamp},v1={digest.hexdigest()}"


def verify(secret: str, body: bytes, header: str, *, tolerance: float = 300.0) -> bool:
    """Whether `header` is a valid signature of `body` made within `tolerance` seconds of now."""
    try:
        parts = dict(item.split("=", 1) for item in header.split(","))
        timestamp = int(parts["t"])
    except (KeyError, ValueError):
        return False
    if abs(time.time() - timestamp) > tolerance:
        return False
    expected = sign(secret, body, timestamp).split("v1=", 1)[1]
    return hmac.compare_digest(expected, parts.get("v1", ""))
