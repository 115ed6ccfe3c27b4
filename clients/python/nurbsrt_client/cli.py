"""nurbsrt-client: the service from a shell script.

    nurbsrt-client --url http://127.0.0.1:8080 render part.step -o part.png --view iso --width 800
    nurbsrt-client convert part.step -o part.stl
    nurbsrt-client upload part.step
The URL and key also come from NURBSRT_URL and NURBSRT_API_KEY."""
from __future__ import annotations

import argparse
import json
import os
import pathlib
import sys

from .client import Client
from .errors import ApiError


def _options(pairs: list[str]) -> dict:
    """--option KEY=VALUE (VALUE as JSON when it parses, else text)."""
    out = {}
    for p in pairs:
        key, sep, value = p.partition("=")
        if not sep:
            raise SystemExit(f"nurbsrt-client: --option wants KEY=VALUE, got {p!r}")
        try:
            out[key] = json.loads(value)
        except ValueError:
            out[key] = value
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="nurbsrt-client", description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--url", default=os.environ.get("NURBSRT_URL", "http://127.0.0.1:8080"))
    ap.add_argument("--api-key", default=os.environ.get("NURBSRT_API_KEY"))
    sub = ap.add_subparsers(dest="command", required=True)
    r = sub.add_parser("render", help="render a model (path or stored id) to an image")
    r.add_argument("model")
    r.add_argument("-o", "--output", required=True)
    r.add_argument("--view")
    r.add_argument("--width", type=int)
    r.add_argument("--height", type=int)
    r.add_argument("--stats", help="write the statistics JSON here")
    r.add_argument("--option", action="append", default=[], metavar="KEY=VALUE", help="any render option")
    c = sub.add_parser("convert", help="convert a model; the format from the output's extension")
    c.add_argument("model")
    c.add_argument("-o", "--output", required=True)
    c.add_argument("--option", action="append", default=[], metavar="KEY=VALUE", help="any conversion option")
    u = sub.add_parser("upload", help="store a model; prints its StoredFile JSON")
    u.add_argument("model")
    a = ap.parse_args(argv)
    client = Client(a.url, api_key=a.api_key)
    try:
        if a.command == "render":
            fmt = pathlib.Path(a.output).suffix.lstrip(".").lower() or "png"
            options = {"view": a.view, "width": a.width, "height": a.height, "format": fmt}
            options.update(_options(a.option))  # --option wins over the flags
            res = client.render(a.model, **options)
            pathlib.Path(a.output).write_bytes(res.image)
            if a.stats:
                pathlib.Path(a.stats).write_text(json.dumps(res.statistics, indent=2) + "\n")
            for w in res.warnings:
                print(f"nurbsrt-client: warning: {w}", file=sys.stderr)
        elif a.command == "convert":
            fmt = pathlib.Path(a.output).suffix.lstrip(".").lower()
            res = client.convert(a.model, fmt, **_options(a.option))
            pathlib.Path(a.output).write_bytes(res.data)
            for w in res.warnings:
                print(f"nurbsrt-client: warning: {w}", file=sys.stderr)
        else:
            print(json.dumps(client.upload(a.model), indent=2))
    except ApiError as e:
        print(f"nurbsrt-client: error [{e.code or e.status}]: {e}", file=sys.stderr)
        return 1
    except OSError as e:
        print(f"nurbsrt-client: error: {e}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
