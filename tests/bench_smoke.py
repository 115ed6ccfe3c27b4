#!/usr/bin/env python3
"""bench_smoke: runs `nurbsrt bench --quick` and checks the SHAPE of its output
(not its speed): every section present, one row per scene, timings finite and
positive, counts non-negative integers, percentages in [0, 100], and the
Markdown report carrying every section. Usage: bench_smoke.py NURBSRT_BINARY"""
import json
import math
import os
import statistics
import subprocess
import sys
import tempfile

SECTIONS = ["table1", "precision", "occt", "tessellation", "meshtracer", "scaling", "look", "batch"]
errors = []


def check(cond, what):
    if not cond:
        errors.append(what)


def get(obj, path):
    for key in path.split("."):
        if not isinstance(obj, dict) or key not in obj:
            return None
        obj = obj[key]
    return obj


def positive(obj, path, where):
    v = get(obj, path)
    check(isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) and v > 0,
          f"{where}: {path} must be a finite positive number, got {v!r}")


def count(obj, path, where):
    v = get(obj, path)
    check(isinstance(v, int) and not isinstance(v, bool) and v >= 0,
          f"{where}: {path} must be a non-negative integer, got {v!r}")


def percent(obj, path, where):
    v = get(obj, path)
    check(isinstance(v, (int, float)) and math.isfinite(v) and 0 <= v <= 100,
          f"{where}: {path} must be a percentage, got {v!r}")


def nonneg(obj, path, where):
    v = get(obj, path)
    check(isinstance(v, (int, float)) and math.isfinite(v) and v >= 0,
          f"{where}: {path} must be finite and >= 0, got {v!r}")


def all_finite(obj, where="doc"):
    if isinstance(obj, dict):
        for k, v in obj.items():
            all_finite(v, f"{where}.{k}")
    elif isinstance(obj, list):
        for i, v in enumerate(obj):
            all_finite(v, f"{where}[{i}]")
    elif isinstance(obj, float):
        check(math.isfinite(obj), f"{where} is not finite")
    elif obj is None:
        errors.append(f"{where} is null")


def main():
    binary = sys.argv[1]
    with tempfile.TemporaryDirectory() as tmp:
        js, md = os.path.join(tmp, "bench.json"), os.path.join(tmp, "bench.md")
        run = subprocess.run([binary, "bench", "--quick", "--json", js, "--markdown", md],
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, timeout=300)
        if run.returncode != 0:
            print(run.stderr)
            print(f"bench_smoke: nurbsrt bench --quick exited with {run.returncode}")
            return 1
        doc = json.load(open(js))
        report = open(md).read()

    all_finite(doc)
    check(doc.get("tool") == "nurbsrt bench" and doc.get("mode") == "quick", "tool/mode")
    m = doc.get("machine", {})
    check(isinstance(m.get("cpu"), str) and m["cpu"], "machine.cpu")
    count(doc, "machine.online_cpus", "machine")
    check(isinstance(m.get("load_average"), list) and len(m["load_average"]) == 3, "machine.load_average")
    check(isinstance(m.get("date_utc"), str) and m["date_utc"].endswith("Z"), "machine.date_utc")
    check(isinstance(m.get("build_type"), str) and m["build_type"], "machine.build_type")
    positive(doc, "elapsed_s", "doc")
    runs = get(doc, "settings.runs")
    check(isinstance(runs, int) and runs >= 1, "settings.runs")
    scenes = doc.get("scenes", [])
    check(len(scenes) == 3, f"3 scenes expected, got {len(scenes)}")
    keys = [s.get("key") for s in scenes]
    for s in scenes:
        positive(s, "faces", f"scene {s.get('key')}")
        positive(s, "import_ms", f"scene {s.get('key')}")
    for sec in SECTIONS:
        check(sec in doc, f"section {sec} missing")
    if errors:
        return report_errors()

    rows = doc["table1"]["rows"]
    check([r["scene"] for r in rows] == keys, "table1: one row per scene")
    for r in rows:
        w = f"table1 {r['scene']}"
        for meth in ("proposed", "martin"):
            for f in ("newton_ms", "newton_primary_ms", "frame_ms", "preliminary_map_ms", "mean_iterations",
                      "pixels_hit", "primary_solves"):
                positive(r, f"{meth}.{f}", w)
            for f in ("failures", "rescued", "converged", "trimmed"):
                count(r, f"{meth}.{f}", w)
            check(len(r[meth]["newton_ms_runs"]) == r["runs"] >= runs, f"{w}: {meth} runs")
            check(r[meth]["frame_ms"] >= r[meth]["newton_ms"] >= r[meth]["newton_primary_ms"],
                  f"{w}: {meth}: frame >= Newton stage >= its first pass")
            nonneg(r, f"{meth}.rescue_ms", w)
        for f in ("speedup_newton_pct", "speedup_frame_pct"):
            check(-1000 < r[f] < 100, f"{w}: {f} = {r[f]}")

    rows = doc["precision"]["rows"]
    check(len(rows) == 2 * len(keys), "precision: two methods per scene")
    for r in rows:
        w = f"precision {r['scene']} {r['method']}"
        for p in ("float32", "rgb8"):
            positive(r, f"{p}.mean_iterations", w)
            positive(r, f"{p}.newton_ms", w)
            count(r, f"{p}.failures", w)
        positive(r, "newton_time_ratio_rgb8_over_float", w)

    rows = doc["occt"]["rows"]
    check([r["scene"] for r in rows] == keys, "occt: one row per scene")
    for r in rows:
        w = f"occt {r['scene']}"
        for f in ("rays", "occt_us_per_ray", "occt_frame_ms_extrapolated", "ours_frame_ms", "occt_over_ours",
                  "occt_load_ms", "both_hit"):
            positive(r, f, w)
        for f in ("hit_agreement_pct", "face_agreement_pct", "dt_within_1e-6_pct"):
            percent(r, f, w)
        for f in ("dt_rel_median", "dt_rel_p99", "dt_rel_max"):
            nonneg(r, f, w)

    t = doc["tessellation"]
    rows = t["rows"]
    check([r["scene"] for r in rows] == keys, "tessellation: one row per scene")
    for r in rows:
        w = f"tessellation {r['scene']}"
        positive(r, "ours.frame_ms", w)
        check(len(r["levels"]) >= 1, f"{w}: no mesh level")
        for lv in r["levels"]:
            lw = f"{w} deflection {lv.get('relative_deflection')}"
            for f in ("relative_deflection", "triangles", "mesh_ms", "raster.render_ms", "raster.total_ms",
                      "raster.both_hit"):
                positive(lv, f, lw)
            for f in ("raster.dz_rel_median", "raster.dz_rel_p99", "raster.dz_rel_max"):
                nonneg(lv, f, lw)
            percent(lv, "raster.hit_disagreement_pct", lw)
            if t["embree"]:
                for f in ("embree.build_ms", "embree.render_ms", "embree.total_ms"):
                    positive(lv, f, lw)

    mt = doc["meshtracer"]
    if mt["embree"]:
        # --quick runs the three scenes only (the four extra models are a full run's).
        check([r["scene"] for r in mt["rows"]] == keys, "meshtracer: one row per scene")
        for r in mt["rows"]:
            w = f"meshtracer {r['scene']}"
            for f in ("faces", "ours_frame_ms", "ours_first_frame_ms", "fine_triangles", "embree_trace_ms",
                      "frame_over_trace", "coarse_triangles", "mesh_first_frame_ms", "first_over_mesh_first"):
                positive(r, f, w)
            check(r["ours_first_frame_ms"] > r["ours_frame_ms"], f"{w}: a first frame includes a frame")
            # The ratios are the medians of alternating pairs' ratios (not of the two medians).
            for f, pairs in (("frame_over_trace", "pairs"), ("first_over_mesh_first", "first_frame_pairs")):
                ratios = r[f + "_pairs"]
                check(len(ratios) == r[pairs] and all(x > 0 for x in ratios), f"{w}: {f}: one positive ratio per pair")
                check(abs(r[f] - statistics.median(ratios)) <= 1e-9 * r[f], f"{w}: {f} is the median of its pairs")
            check(r["fine_triangles"] > r["coarse_triangles"], f"{w}: the fine mesh has more triangles")
    else:
        print("bench_smoke: Embree not built in: meshtracer figures not checked")

    sc = doc["scaling"]
    res = sc["resolution"]["rows"]
    check(len(res) >= 2 and all(a["size"] < b["size"] for a, b in zip(res, res[1:])), "scaling: sizes increase")
    for r in res:
        positive(r, "frame_ms", f"scaling resolution {r.get('size')}")
        positive(r, "ns_per_pixel", f"scaling resolution {r.get('size')}")
    check(len(sc["patches"]["rows"]) >= len(keys), "scaling: patch rows")
    for r in sc["patches"]["rows"]:
        positive(r, "patches", f"scaling patches {r.get('scene')}")
        positive(r, "frame_ms", f"scaling patches {r.get('scene')}")
    check([r["scene"] for r in sc["threads_scaling"]["rows"]] == keys, "scaling threads: one row per scene")
    for r in sc["threads_scaling"]["rows"]:
        for f in ("threads_1.frame_ms", "threads_2.frame_ms", "frame_speedup", "newton_speedup"):
            positive(r, f, f"scaling threads {r['scene']}")

    lk = doc["look"]
    check([r["scene"] for r in lk["rows"]] == keys, "look: one row per scene")
    for r in lk["rows"]:
        w = f"look {r['scene']}"
        for v in ("plain", "aa_edges", "shadows", "section", "ground"):
            positive(r, f"{v}.frame_ms", w)
            positive(r, f"{v}.frame_ms_min", w)
            check(len(r[v]["frame_ms_runs"]) == r["runs"] >= runs, f"{w}: {v} runs")
            for st in ("map", "newton", "shade", "antialias", "edges", "shadow_map"):
                nonneg(r, f"{v}.stages_ms.{st}", w)
        # Each variant's own stages ran, and only those.
        positive(r, "aa_edges.stages_ms.edges", w)
        positive(r, "aa_edges.antialias_rays", w)
        positive(r, "shadows.stages_ms.shadow_map", w)
        positive(r, "shadows.shadow_rays", w)
        check(r["plain"]["antialias_rays"] == 0 and r["plain"]["shadow_rays"] == 0, f"{w}: plain traced extra rays")
        nonneg(r, "section_cap_pixels", w)  # open shells (the ducks) have no caps
        positive(r, "ground.shadow_rays", w)
        for ratio in ("aa_edges_over_plain", "shadows_over_plain", "section_over_plain", "ground_over_plain"):
            for f in ("median", "min", "pair_median", "target"):
                positive(r, f"{ratio}.{f}", w)
            check(isinstance(get(r, f"{ratio}.meets_target"), bool), f"{w}: {ratio}.meets_target")
        check(abs(r["aa_edges_over_plain"]["median"] - r["aa_edges"]["frame_ms"] / r["plain"]["frame_ms"]) < 1e-9 *
              r["aa_edges_over_plain"]["median"] + 1e-12, f"{w}: aa_edges/plain is the ratio of the medians")

    sheet = lk["sheet"]
    for f in ("sheet_ms", "separate_ms", "sheet_over_separate", "target"):
        positive(sheet, f, "look sheet")
    check(sheet["sheet_ms"] < sheet["separate_ms"], "look sheet: one import for four views costs less than four")
    check("Contact sheet" in report, "Markdown report lacks the contact sheet line")

    bt = doc["batch"]
    check(len(bt["files"]) >= 4 and bt["outputs"] == 3 * len(bt["files"]), "batch: files x (render, STL, glb)")
    check(len(bt["runs"]) >= 1, "batch: runs")
    for r in bt["runs"]:
        for f in ("cli_loop_ms", "job_ms", "ratio"):
            positive(r, f, "batch")
        check(r["cli_loop_stages"]["reads"] == bt["outputs"], "batch: the CLI loop reads each output's file")
        check(r["job_stages"]["reads"] == len(bt["files"]), "batch: the job reads each file once")
        for side in ("cli_loop_stages", "job_stages"):
            for f in ("read_ms", "render_ms", "write_ms"):
                positive(r, f"{side}.{f}", "batch")
    check(bt["last_job_statistics"]["reads"] == len(bt["files"]), "batch: the job document counts one read a file")
    for heading in ("## Table 1", "## Map precision", "## Exact peer", "## Tessellating peer",
                    "## Frame vs mesh tracer", "## Scaling", "## Image options", "## Batch job"):
        check(heading in report, f"Markdown report lacks '{heading}'")
    for k in keys:
        check(k in report, f"Markdown report lacks scene {k}")
    return report_errors()


def report_errors():
    for e in errors:
        print("bench_smoke: FAIL", e)
    if not errors:
        print("bench_smoke: output shape OK")
    return 1 if errors else 0


if __name__ == "__main__":
    sys.exit(main())
