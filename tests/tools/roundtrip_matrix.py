#!/usr/bin/env python3
"""The round-trip matrix: real models of ../shared/models through
STEP -> IGES -> STEP, STEP -> BREP -> STEP and IGES -> STEP -> IGES with
`nurbsrt convert --report`, each step's fidelity report kept, and the end of
each chain compared with its start from the reports' absolute measures
(counts, volume, area, box; coloured faces, names; units).

Usage: tests/tools/roundtrip_matrix.py build/nurbsrt OUT_DIR
Writes OUT_DIR/roundtrip_matrix.json (every report) and OUT_DIR/ROUNDTRIP.md
(the table). Skips, saying so, when ../shared/models is absent."""
import json
import math
import os
import subprocess
import sys
import tempfile
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
MODELS = Path(os.environ.get("NURBSRT_MODELS", REPO.parent / "shared" / "models"))
# Mechanical, free-form, assemblies, inch and mm, both formats.
STEP_MODELS = ["as1-oc-214.stp", "box_sides.STEP", "featuretype.STEP", "cube-in.step", "screw.step",
               "bug3883_xr2-ct-214_bolt.stp", "face_recognition_sample_part.stp", "trj2_io1-ca-214.stp",
               "red_cube_blue_cylinder.step", "splinecage.stp", "bug27693_cornetta-step.stp", "linkrods.step",
               "eight_cyl.stp", "cylinder_block.stp"]
IGES_MODELS = ["as1_pe_203.igs", "bearing.iges", "hammer.iges", "sunglasses_lens.igs", "torus.igs",
               "occ22470.igs", "ship_kcs.igs"]
CHAINS = {"step": [("iges", ".igs"), ("brep", ".brep")], "iges": [("step", ".step")]}
EXACT = 1e-6  # the reports' tolerance for exact formats


def convert(exe, src, dst, report):
    run = subprocess.run([exe, "convert", "-q", "--report", report, src, dst], capture_output=True, text=True)
    if run.returncode != 0:
        return None, run.stderr.strip()
    return json.loads(Path(report).read_text()), ""


def rel(a, b):
    return 0.0 if a == b else abs(a - b) / max(abs(a), abs(b))


def box_move(a, b):
    lo_a, hi_a, lo_b, hi_b = a["min"], a["max"], b["min"], b["max"]
    diag = math.dist(lo_a, hi_a)
    move = max(max(abs(x - y) for x, y in zip(lo_a, lo_b)), max(abs(x - y) for x, y in zip(hi_a, hi_b)))
    return move / diag if diag > 0 else move


def chain(exe, tmp, model, fmt, mid_fmt, mid_ext):
    back_ext = ".step" if fmt == "step" else ".igs"
    mid, back = Path(tmp) / ("mid" + mid_ext), Path(tmp) / ("back" + back_ext)
    r1, e1 = convert(exe, str(model), str(mid), str(Path(tmp) / "r1.json"))
    if r1 is None:
        return {"error": e1}
    r2, e2 = convert(exe, str(mid), str(back), str(Path(tmp) / "r2.json"))
    if r2 is None:
        return {"error": e2, "first": r1}
    a, b = r1["source"]["geometry"], r2["output"]["geometry"]
    end = {k: [a[k], b[k]] for k in ("solids", "shells", "faces", "edges")}
    end["volume"] = rel(a["volume"], b["volume"]) if a["solids"] and b["solids"] else None
    end["area"] = rel(a["area"], b["area"])
    end["box"] = box_move(a["box"], b["box"])
    end["valid"] = [a["valid"], b["valid"]]
    end["units"] = [r1["source"]["units"], r1["output"]["units"], r2["output"]["units"]]
    at1, at2 = r1.get("attributes", {}), r2.get("attributes", {})
    end["coloured_faces"] = [at1.get("colours", {}).get("source_coloured_faces"),
                             at2.get("colours", {}).get("output_coloured_faces")]
    end["names"] = [at1.get("names", {}).get("source"), at2.get("names", {}).get("output")]
    end["instances"] = [at1.get("assembly", {}).get("source", {}).get("instances"),
                        at2.get("assembly", {}).get("output", {}).get("instances")]
    return {"end_to_end": end, "first": r1, "second": r2}


def fmt_rel(x):
    return "-" if x is None else f"{x:.1e}"


def main():
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    exe, out = sys.argv[1], Path(sys.argv[2])
    if not MODELS.is_dir():
        print(f"roundtrip_matrix: {MODELS} is absent: nothing to do")
        return
    out.mkdir(parents=True, exist_ok=True)
    results, rows = {}, []
    for fmt, names in (("step", STEP_MODELS), ("iges", IGES_MODELS)):
        for name in names:
            model = MODELS / fmt / name
            if not model.is_file():
                print(f"roundtrip_matrix: {model} is absent: skipped")
                continue
            for mid_fmt, mid_ext in CHAINS[fmt]:
                key = f"{name}: {fmt} -> {mid_fmt} -> {fmt}"
                with tempfile.TemporaryDirectory() as tmp:
                    results[key] = chain(exe, tmp, model, fmt, mid_fmt, mid_ext)
                r = results[key]
                if "error" in r:
                    rows.append(f"| {name} | {fmt.upper()}->{mid_fmt.upper()}->{fmt.upper()} | error: {r['error'][:80]} |"
                                + " |" * 9)
                    continue
                e = r["end_to_end"]
                same = all(e[k][0] == e[k][1] for k in ("solids", "faces")) and \
                    all(x is None or x <= EXACT for x in (e["volume"], e["area"], e["box"]))
                lost = sorted(set(r["first"].get("warnings", []) + r["second"].get("warnings", [])))
                rows.append(
                    f"| {name} | {fmt.upper()}->{mid_fmt.upper()}->{fmt.upper()} | {'yes' if same else '**no**'} | "
                    f"{e['solids'][0]}->{e['solids'][1]} | {e['faces'][0]}->{e['faces'][1]} | "
                    f"{fmt_rel(e['volume'])} | {fmt_rel(e['area'])} | {fmt_rel(e['box'])} | "
                    f"{e['coloured_faces'][0]}->{e['coloured_faces'][1]} | {e['names'][0]}->{e['names'][1]} | "
                    f"{'/'.join(u or '-' for u in e['units'])} | {len(lost)} |")
                print(rows[-1], flush=True)
    (out / "roundtrip_matrix.json").write_text(json.dumps(results, indent=1) + "\n")
    head = ("| model | chain | solids, faces equal; volume, area, box within 1e-6 | solids | faces | volume | area | box "
            "| coloured faces | names | units (source/middle/end) | warnings on the way |\n"
            "|---|---|---|---|---|---|---|---|---|---|---|---|\n")
    (out / "ROUNDTRIP.md").write_text(
        "# Round-trip matrix\n\nWritten by `tests/tools/roundtrip_matrix.py build/nurbsrt docs/fidelity` from the "
        "fidelity reports of `nurbsrt convert --report` (all of them in roundtrip_matrix.json, with every warning). "
        "End of each chain against its start; relative differences; names and coloured faces counted as XDE reads "
        "them.\n\n" + head + "\n".join(rows) + "\n")


if __name__ == "__main__":
    main()
