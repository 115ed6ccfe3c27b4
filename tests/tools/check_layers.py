#!/usr/bin/env python3
"""The repository's layering, checked from the #include lines (docs/DESIGN.md, "Layers").

- core/ includes only core/; importer/ no renderer internals, options/, server/ or cli/.
- core/ and importer/: the headers on top are their public interface and include
  no room; a room includes the top and lower rooms only (core: process < scene <
  io; importer: faces < convert < reference); the .cpp files on top, any room.
- options/ (the request model of the CLI and the server) includes core/, the
  public headers of renderer/ and importer/importer.h, and itself.
- renderer/: the public headers (renderer/*.h) include only core/ and each other;
  a room includes the public headers and lower rooms only (solve < map < frame <
  passes < output); render.cpp and frame_cost.cpp, on top, may include any room.
- server/: a room includes only lower rooms (common < store < http < render <
  jobs < routes); server.cpp, on top, any.
- Outside renderer/, only its public headers (tests and the benchmark's mesh
  rasterizer, which shares the GL context, excepted).
- OCCT headers (*.hxx) only in importer/ (and tests/, which use OCCT as the reference).
- No product folder over kMaxFiles files, but for the ones listed as debts.
Prints each violation; exit status 1 if any.
"""
import os
import re
import sys

ROOT = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))
RENDERER_ROOMS = ["solve", "map", "frame", "passes", "output"]
SERVER_ROOMS = ["common", "store", "http", "render", "jobs", "routes"]
PUBLIC_TOP_ROOMS = {"core": ["process", "scene", "io"], "importer": ["faces", "convert", "reference"]}
PRODUCT = ["core", "importer", "renderer", "options", "server", "cli", "bench", "fuzz"]
kMaxFiles = 20
INCLUDE = re.compile(r'^\s*#\s*include\s*([<"])([^>"]+)[>"]', re.M)


def sources():
    for top in PRODUCT + ["tests"]:
        for d, _, files in os.walk(os.path.join(ROOT, top)):
            for f in files:
                if f.endswith((".h", ".cpp")):
                    yield os.path.relpath(os.path.join(d, f), ROOT)


def room(path, top):
    parts = path.split("/")
    return parts[1] if parts[0] == top and len(parts) > 2 else ""


def check(path, kind, inc):
    top = path.split("/")[0]
    if kind == "<":
        if inc.endswith(".hxx") and top not in ("importer", "tests"):
            return "OCCT header outside importer/"
        return None
    itop = inc.split("/")[0]
    if top == "core" and itop != "core":
        return "core/ includes only core/"
    if top == "options" and (itop in ("server", "cli", "bench") or (itop == "importer" and inc != "importer/importer.h")):
        return "options/ includes core/, public renderer headers, importer/importer.h and itself"
    if top == "importer" and (itop in ("options", "server", "cli", "bench") or (itop == "renderer" and room(inc, "renderer"))):
        return "importer/ includes no renderer internals, server/ or cli/"
    if itop == "renderer" and room(inc, "renderer"):
        if top == "renderer":
            here = room(path, "renderer")
            if here == "":
                if path.endswith(".h"):
                    return "a public renderer header includes a room"
            elif here != "output" or "image_writer" not in path:
                if RENDERER_ROOMS.index(room(inc, "renderer")) > RENDERER_ROOMS.index(here):
                    return "a renderer room includes a higher room"
        elif top not in ("tests",) and path != "bench/mesh_raster.cpp":
            return "renderer internals included from outside renderer/"
    if top in PUBLIC_TOP_ROOMS and itop == top and room(inc, top):
        rooms, here, there = PUBLIC_TOP_ROOMS[top], room(path, top), room(inc, top)
        if there not in rooms:
            return f"{top}/{there}/ is not a room of {top}/ (tests/tools/check_layers.py)"
        if here == "":
            if path.endswith(".h"):
                return f"a header on top of {top}/ includes a room"
        elif here not in rooms or rooms.index(there) > rooms.index(here):
            return f"a {top}/ room includes a higher room"
    if top == "server" and itop == "server":
        here = room(path, "server")
        if here:
            there = room(inc, "server")
            if not there or SERVER_ROOMS.index(there) > SERVER_ROOMS.index(here):
                return "a server room includes a higher room or server.h"
    if top in ("core", "importer", "renderer") and itop in ("options", "server", "cli", "bench"):
        return "a lower layer includes a higher one"
    return None


def main():
    bad = []
    for path in sources():
        text = open(os.path.join(ROOT, path), encoding="utf-8").read()
        for kind, inc in INCLUDE.findall(text):
            why = check(path, kind, inc)
            if why:
                bad.append(f"{path}: #include {inc}: {why}")
    for top in PRODUCT:
        for d, _, files in os.walk(os.path.join(ROOT, top)):
            n = sum(1 for f in files if f.endswith((".h", ".cpp")))
            rel = os.path.relpath(d, ROOT)
            if n > kMaxFiles:
                bad.append(f"{rel}/: {n} files, more than {kMaxFiles}")
    for line in bad:
        print(line)
    print(f"check_layers: {len(bad)} violation(s)")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
