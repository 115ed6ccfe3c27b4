"""From file to image, whole process: `nurbsrt render FILE -o x.png` against
OCCT's own viewer scripted for the same thumbnail (DRAW: read the file, mesh it
at its default deflection, display it shaded with OpenGL, dump a PNG), the same
files, the same size, interleaved.

OCCT's viewer needs an X display: one Xvfb server runs for the whole benchmark
and only the `occt-draw` process is timed, so the peer pays no X start-up.
Both draw with Mesa's llvmpipe. Each round runs every model through both tools,
the order of the two swapped every round (so neither always runs on the other's
warm file cache). Prints per model the median wall time of each, their ratio
(ours / OCCT's), the machine's load, and writes the same as JSON.

Usage: python3 bench/occt_viewer.py [path/to/nurbsrt] [out.json]
Settings (environment): ROUNDS (5), SIZE (512), MODELS (space-separated
STEP/IGES files; default: the table below where ../shared/models has them).
Needs Debian's occt-draw, libocct-draw-dev and xvfb (scripts/setup.sh installs
them).
"""
import json
import os
import pathlib
import platform
import shutil
import statistics
import subprocess
import sys
import tempfile
import time

ROOT = pathlib.Path(__file__).resolve().parent.parent
SHARED = ROOT.parent / "shared" / "models"
# Parts from several CAD systems and sizes: free-form consumer parts,
# mechanical parts, an assembly, IGES solids and surfaces.
TABLE = [
    "step/bug27693_cornetta-step.stp",
    "step/trj8_b1-ec-214.stp",
    "step/cylinder_block.stp",
    "step/as1-oc-214.stp",
    "step/featuretype.STEP",
    "step/linkrods.step",
    "step/screw.step",
    "iges/bearing.iges",
    "iges/heartValve.igs",
    "iges/BUC50025.igs",
]
# OCCT's thumbnail as its viewer makes one (the recipe of its own test scripts).
DRAW_SCRIPT = """pload MODELING VISUALIZATION DATAEXCHANGE
{read} {path} s
vinit View1 w={size} h={size}
vdisplay -dispMode 1 s
vaxo
vfit
vdump {out}
exit
"""


def default_models():
    found = [SHARED / m for m in TABLE if (SHARED / m).is_file()]
    return found or [pathlib.Path("/usr/share/opencascade/data/step/screw.step")]


def timed(cmd, env=None):
    t0 = time.perf_counter()
    done = subprocess.run(cmd, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT)
    wall = time.perf_counter() - t0
    if done.returncode != 0:
        raise SystemExit(f"failed ({done.returncode}): {' '.join(map(str, cmd))}\n{done.stdout.decode()[-2000:]}")
    return wall


def start_xvfb():
    for display in range(90, 120):
        if pathlib.Path(f"/tmp/.X11-unix/X{display}").exists() or pathlib.Path(f"/tmp/.X{display}-lock").exists():
            continue
        proc = subprocess.Popen(["Xvfb", f":{display}", "-screen", "0", "1280x1024x24", "-nolisten", "tcp"],
                                stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        for _ in range(100):
            if pathlib.Path(f"/tmp/.X11-unix/X{display}").exists():
                return proc, f":{display}"
            time.sleep(0.05)
        proc.kill()
    raise SystemExit("cannot start Xvfb")


def main():
    exe = sys.argv[1] if len(sys.argv) > 1 else str(ROOT / "build" / "nurbsrt")
    out_json = sys.argv[2] if len(sys.argv) > 2 else None
    rounds = int(os.environ.get("ROUNDS", "5"))
    size = os.environ.get("SIZE", "512")
    models = [pathlib.Path(m) for m in os.environ.get("MODELS", "").split()] or default_models()
    for tool in ("occt-draw", "Xvfb"):
        if not shutil.which(tool):
            raise SystemExit(f"{tool} is not installed (scripts/setup.sh installs occt-draw and xvfb)")
    xvfb, display = start_xvfb()
    env = dict(os.environ, DISPLAY=display)
    load_before = os.getloadavg()
    times = {str(m): {"nurbsrt": [], "occt": []} for m in models}
    try:
        with tempfile.TemporaryDirectory(prefix="nurbsrt-occt-viewer-") as tmp:
            tmp = pathlib.Path(tmp)
            scripts = {}
            for k, m in enumerate(models):
                read = "testreadiges" if m.suffix.lower() in (".igs", ".iges") else "testreadstep"
                script = tmp / f"m{k}.tcl"
                script.write_text(DRAW_SCRIPT.format(read=read, path=m, size=size, out=tmp / f"occt{k}.png"))
                scripts[str(m)] = script
            for r in range(rounds):
                for k, m in enumerate(models):
                    ours = [exe, "render", str(m), "-o", str(tmp / f"ours{k}.png"), "--width", size, "--height", size,
                            "--quiet"]
                    theirs = ["occt-draw", "-b", "-f", str(scripts[str(m)])]
                    pair = [("nurbsrt", ours, None, tmp / f"ours{k}.png"), ("occt", theirs, env, tmp / f"occt{k}.png")]
                    if (r + k) % 2:
                        pair.reverse()
                    for name, cmd, e, png in pair:
                        png.unlink(missing_ok=True)
                        times[str(m)][name].append(timed(cmd, e))
                        # DRAW exits 0 whatever its commands did: the image is the proof of work.
                        if not png.is_file() or png.stat().st_size == 0:
                            raise SystemExit(f"{name} wrote no image for {m}")
                print(f"round {r + 1}/{rounds} done", file=sys.stderr)
    finally:
        xvfb.terminate()
        xvfb.wait()
    load_after = os.getloadavg()
    rows = []
    for m in models:
        t = times[str(m)]
        ours, theirs = statistics.median(t["nurbsrt"]), statistics.median(t["occt"])
        rows.append({"model": m.name, "nurbsrt_s": ours, "occt_s": theirs, "ratio": ours / theirs,
                     "nurbsrt_runs": t["nurbsrt"], "occt_runs": t["occt"]})
    print(f"| model | nurbsrt render s | OCCT viewer s | ours / OCCT |\n|---|---:|---:|---:|")
    for row in rows:
        print(f"| {row['model']} | {row['nurbsrt_s']:.2f} | {row['occt_s']:.2f} | **{row['ratio']:.2f}** |")
    print(f"\n{platform.node()}, {os.cpu_count()} cores, {rounds} rounds, {size}x{size}; "
          f"load {load_before[0]:.2f} before, {load_after[0]:.2f} after")
    if out_json:
        pathlib.Path(out_json).write_text(json.dumps(
            {"size": int(size), "rounds": rounds, "load_before": load_before[0], "load_after": load_after[0],
             "rows": rows}, indent=2) + "\n")


if __name__ == "__main__":
    main()
