"""nurbsrt-client: the service from a shell script.

    nurbsrt-client --url http://127.0.0.1:8080 render part.step -o part.png --view iso --width 800
    nurbsrt-client convert part.step -o part.stl
    nurbsrt-client upload part.step
    nurbsrt-client job a.step b.iges --render width=800,view=iso --convert stl -d out/
The URL and key also come from NURBSRT_URL and NURBSRT_API_KEY."""
from __future__ import annotations

import argparse
import json
import os
import pathlib
import sys

from .client import Client, Progress
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


def _job_outputs(a: argparse.Namespace) -> list[dict]:
    outputs = []
    for f in range(len(a.models)):
        for r in a.render:
            outputs.append({"file": f, "type": "render", "options": _options([p for p in r.split(",") if p])})
        outputs += [{"file": f, "type": "conversion", "format": fmt} for fmt in a.convert]
    if not outputs:
        raise SystemExit("nurbsrt-client: job wants at least one --render or --convert")
    return outputs


def _print_progress(p: Progress) -> None:
    print(f"nurbsrt-client: {p.state} {p.fraction:4.0%} ({p.outputs_done}/{p.outputs_total} outputs, "
          f"{p.artifact_bytes} bytes)", file=sys.stderr, flush=True)


def _run_job(client: Client, a: argparse.Namespace) -> int:
    """Submits, waits printing the progress (a line per change), downloads, prints the Job JSON;
    exit status 1 when the job failed."""
    job = client.submit_job(a.models, _job_outputs(a))
    print(f"nurbsrt-client: job {job['id']}", file=sys.stderr, flush=True)
    final = client.wait(job["id"], progress=_print_progress)
    if a.directory:
        out = pathlib.Path(a.directory)
        out.mkdir(parents=True, exist_ok=True)
        for o in final["outputs"]:
            if o["state"] == "succeeded":
                client.download(o, out / o["artifact"]["name"])
    print(json.dumps(final, indent=2))
    return 0 if final["state"] == "succeeded" else 1


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
    j = sub.add_parser("job", help="run a batch job over the models, printing its progress; downloads its artifacts")
    j.add_argument("models", nargs="+")
    j.add_argument("--render", action="append", default=[], metavar="KEY=VALUE,...",
                   help="a render of every model with these options (repeatable; '' for the defaults)")
    j.add_argument("--convert", action="append", default=[], metavar="FORMAT", help="a conversion of every model")
    j.add_argument("-d", "--directory", help="download the artifacts here")
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
        elif a.command == "job":
            return _run_job(client, a)
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
