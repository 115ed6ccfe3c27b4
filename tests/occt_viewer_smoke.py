#!/usr/bin/env python3
"""occt_viewer_smoke: runs bench/occt_viewer.py for one round on OCCT's screw.step
and checks the SHAPE of its JSON (not its speed): one row, both tools timed
with positive finite times, the ratio theirs / ours consistent. The script
itself fails when either tool writes no image. Usage: occt_viewer_smoke.py NURBSRT_BINARY"""
import json
import math
import os
import pathlib
import subprocess
import sys
import tempfile

ROOT = pathlib.Path(__file__).resolve().parent.parent
model = "/usr/share/opencascade/data/step/screw.step"
with tempfile.TemporaryDirectory() as tmp:
    out = pathlib.Path(tmp) / "occt_viewer.json"
    env = dict(os.environ, ROUNDS="1", SIZE="256", MODELS=model)
    subprocess.run([sys.executable, str(ROOT / "bench" / "occt_viewer.py"), sys.argv[1], str(out)], env=env,
                   check=True)
    d = json.loads(out.read_text())
rows = d["rows"]
assert len(rows) == 1 and rows[0]["model"] == "screw.step", rows
r = rows[0]
for key in ("nurbsrt_s", "occt_s"):
    assert math.isfinite(r[key]) and r[key] > 0, (key, r)
assert abs(r["ratio"] - r["nurbsrt_s"] / r["occt_s"]) < 1e-9, r
print(f"occt_viewer_smoke: ok (screw.step 256^2: nurbsrt {r['nurbsrt_s']:.2f} s, OCCT viewer {r['occt_s']:.2f} s)")
