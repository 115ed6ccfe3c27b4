"""Checking a job webhook's signature: X-Nurbsrt-Signature is "sha256=" and the hex
HMAC-SHA256 of the request body under the service's webhook secret."""
from __future__ import annotations

import hashlib
import hmac


def verify_signature(secret: str | bytes, body: bytes, signature_header: str | None) -> bool:
    """True when `signature_header` is the signature of `body` under `secret` (constant-time compare)."""
    if not signature_header:
        return False
    key = secret.encode() if isinstance(secret, str) else secret
    expected = "sha256=" + hmac.new(key, body, hashlib.sha256).hexdigest()
    return hmac.compare_digest(signature_header.strip(), expected)
