"""Client for the nurbsrt service (its OpenAPI document: GET /openapi.json).

    from nurbsrt_client import Client
    c = Client("http://127.0.0.1:8080", api_key=None)
    r = c.render("part.step", view="iso", width=800, height=600)
    open("part.png", "wb").write(r.image)
"""
from .client import Client, Conversion, Event, Progress, Render, parse_sse
from .errors import ApiError, InvalidRequest, NotFound, Unavailable, TooLarge, Unprocessable, error_for
from .webhooks import verify_signature

__all__ = ["Client", "Conversion", "Event", "Progress", "Render", "parse_sse",
           "ApiError", "InvalidRequest", "NotFound", "Unavailable", "TooLarge",
           "Unprocessable", "error_for", "verify_signature"]
