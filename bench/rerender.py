"""Cached re-render through the service: what a request costs beyond its frame.

Starts `nurbsrt serve` on a free loopback port with a temporary data dir, sends
each model once (the import fills the scene cache), then asks for it again in
other views and reads each answer's Server-Timing header. Two ways a client
asks again: with the file in every request (`upload`), or by the id of a stored
file (`stored`: POST /v1/files once, then `file_id`), the way to render many
views of one model. The
frame is the sum of the frame's stages (preliminary_map, newton, shadow_map,
shade, antialias, edges); the request is `total`, from its arrival to its
answer (reading the upload, the cache lookup, the encoding, the statistics).
Prints a Markdown table per model, way and format: the median frame, the median
total and the median of total / frame, with the median of each other stage
(`other`: the rest, mostly starting and joining the render's thread).

Usage: python3 bench/rerender.py [path/to/nurbsrt]
Settings (environment): ROUNDS (views per model and format, 21), SIZE (512),
FORMATS ("png tiff"; png is the API's default, with anti-aliasing),
RENDER_THREADS (0: all cores, the service's default), MODELS (space-separated
files; default: the Table-1 models of ../shared/models, else OCCT's samples).
"""
import os
import pathlib
import re
import statistics
import subprocess
import sys
import tempfile
import time

import requests

ROOT = pathlib.Path(__file__).resolve().parent.parent
FRAME_STAGES = ("preliminary_map", "newton", "shadow_map", "shade", "antialias", "edges")
# The views a catalogue asks for (named views of the API); the first request of
# a model (the import) uses the fitted default and is not counted.
VIEWS = ("iso", "front", "top", "right", "back", "left", "bottom")


def default_models():
    shared = ROOT.parent / "shared" / "models"
    table1 = [shared / "step/bug27693_cornetta-step.stp", shared / "step/trj8_b1-ec-214.stp",
              shared / "duck/duck_from_glscene.igs"]
    if all(p.is_file() for p in table1):
        return table1
    print("rerender.py: ../shared/models absent; OCCT's sample files instead", file=sys.stderr)
    occt = pathlib.Path("/usr/share/opencascade/data")
    return [occt / "step/screw.step", occt / "iges/bearing.iges"]


def server_timing(header):
    return {name: float(ms) for name, ms in re.findall(r"(\w+);dur=([\d.]+)", header)}


def render(url, source, options):
    """source: ("file", (name, bytes, type)) or ("file_id", (None, id))."""
    r = requests.post(url + "/v1/renders", files=[source, ("options", (None, options, "application/json"))],
                      timeout=300)
    r.raise_for_status()
    return server_timing(r.headers["Server-Timing"]), "desc=hit" in r.headers["Server-Timing"]


def stored(url, name, data):
    r = requests.post(url + "/v1/files", files=[("file", (name, data, "application/octet-stream"))], timeout=300)
    r.raise_for_status()
    return r.json()["id"]


def measure(url, source, fmt, size, rounds):
    """The table's figures for one model, way and format: the first request may
    import, then `rounds` views that the scene cache must answer."""
    render(url, source, f'{{"format":"{fmt}","width":{size},"height":{size}}}')
    rows = []
    for k in range(rounds):
        options = f'{{"format":"{fmt}","width":{size},"height":{size},"view":"{VIEWS[k % len(VIEWS)]}"}}'
        t, hit = render(url, source, options)
        if not hit:
            sys.exit(f"rerender.py: {source[1][0] or source[1][1]} missed the scene cache")
        rows.append(t)
    frame = [sum(t.get(s, 0.0) for s in FRAME_STAGES) for t in rows]
    med = lambda key: statistics.median(t.get(key, 0.0) for t in rows)
    other = statistics.median(t["total"] - f - sum(t.get(s, 0.0) for s in ("upload", "encode", "cache", "statistics"))
                              for t, f in zip(rows, frame))
    ratio = statistics.median(t["total"] / f for t, f in zip(rows, frame))
    return (f"{statistics.median(frame):.1f} | {med('total'):.1f} | **{ratio:.2f}** | {med('upload'):.1f} | "
            f"{med('encode'):.1f} | {med('cache'):.1f} | {med('statistics'):.1f} | {other:.1f}")


def main():
    binary = pathlib.Path(sys.argv[1] if len(sys.argv) > 1 else ROOT / "build/nurbsrt").resolve()
    rounds = int(os.environ.get("ROUNDS", "21"))
    size = int(os.environ.get("SIZE", "512"))
    formats = os.environ.get("FORMATS", "png tiff").split()
    models = [pathlib.Path(m) for m in os.environ["MODELS"].split()] if os.environ.get("MODELS") else default_models()
    with tempfile.TemporaryDirectory() as tmp:
        port_file = pathlib.Path(tmp) / "port"
        server = subprocess.Popen([str(binary), "serve", "--port", "0", "--port-file", str(port_file),
                                   "--data-dir", str(pathlib.Path(tmp) / "data"),
                                   "--render-threads", os.environ.get("RENDER_THREADS", "0")],
                                  stderr=subprocess.DEVNULL)
        try:
            while not (port_file.exists() and port_file.read_text().strip()):
                if server.poll() is not None:
                    sys.exit("rerender.py: the service did not start")
                time.sleep(0.05)
            url = f"http://127.0.0.1:{port_file.read_text().strip()}"
            print(f"{size}x{size}, {rounds} cached views per row, render threads "
                  f"{os.environ.get('RENDER_THREADS', '0')} (0: all {os.cpu_count()} cores)\n")
            print("| model | way | format | frame ms | total ms | total / frame | upload | encode | cache | statistics "
                  "| other |")
            print("|---|---|---|---|---|---|---|---|---|---|---|")
            for model, way, fmt in [(m, w, f) for m in models for w in ("upload", "stored") for f in formats]:
                data = model.read_bytes()
                source = (("file", (model.name, data, "application/octet-stream")) if way == "upload" else
                          ("file_id", (None, stored(url, model.name, data))))
                print(f"| {model.name} | {way} | {fmt} | " + measure(url, source, fmt, size, rounds) + " |")
        finally:
            server.terminate()
            server.wait()


if __name__ == "__main__":
    main()
