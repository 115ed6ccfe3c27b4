"""problem+json answers (RFC 9457) as typed exceptions carrying the service's error code."""
from __future__ import annotations

from typing import Any


class ApiError(Exception):
    """A non-2xx answer: HTTP status, the problem's code (invalid_argument, not_found, ...),
    title, detail and the request id to quote in a report."""

    def __init__(self, status: int, problem: dict[str, Any] | None, text: str = ""):
        problem = problem or {}
        self.status = status
        self.code: str = problem.get("code", "")
        self.title: str = problem.get("title", f"HTTP {status}")
        self.detail: str = problem.get("detail", text[:300])
        self.request_id: str = problem.get("request_id", "")
        self.problem = problem
        super().__init__(f"{self.title}: {self.detail} (HTTP {status}{', ' + self.code if self.code else ''})")


class InvalidRequest(ApiError):
    """400: an option or the request itself is wrong (the detail names the field)."""


class NotFound(ApiError):
    """404: no such file, job or artifact."""


class TooLarge(ApiError):
    """413 or 507: the upload, the model or the storage is over a limit."""


class Unprocessable(ApiError):
    """415 or 422: the file is not STEP/IGES/BREP, or cannot be read, or a strict conversion refused."""


class Unavailable(ApiError):
    """429 or 503: the service is busy (retried by the client after Retry-After) or not ready."""


_BY_STATUS = {400: InvalidRequest, 404: NotFound, 413: TooLarge, 507: TooLarge, 415: Unprocessable,
              422: Unprocessable, 429: Unavailable, 503: Unavailable}


def error_for(status: int, problem: dict[str, Any] | None, text: str = "") -> ApiError:
    """The exception class of an answer's status, built from its problem document."""
    return _BY_STATUS.get(status, ApiError)(status, problem, text)
