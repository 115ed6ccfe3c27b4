"""Statistics that add up: the stage times of a render or a conversion sum to
its total (JSON timings_ms and Server-Timing alike), every stage is >= 0, and
the Newton counts agree with their iteration histogram."""
import json
import os
import time

import requests

from conftest import BEARING, SCREW, TIMEOUT, server_timing, validate

JSON = {"Accept": "application/json"}
TOLERANCE = 0.02  # the stages sum to total within 2 %
RENDER_STAGES = ["upload", "cache", "queue", "prescan", "isolation", "read", "nurbs_convert", "mesh", "transfer",
                 "prepare", "frame_setup", "preliminary_map", "newton", "shadow_map", "shade", "antialias", "edges",
                 "statistics", "encode", "response"]
CONVERSION_STAGES = ["upload", "queue", "prescan", "isolation", "read", "mesh", "write", "verify", "transfer",
                     "response"]


def check_adds_up(timings, stages, what):
    """timings: {stage: ms, ..., "total": ms}."""
    t = dict(timings)
    total = t.pop("total")
    assert set(stages) <= set(t), (what, sorted(set(stages) - set(t)))
    assert all(v >= 0 for v in t.values()), (what, t)
    assert total > 0, (what, total)
    s = sum(t.values())
    # The stages are the whole request, not a sample of it.
    assert abs(s - total) <= TOLERANCE * total, f"{what}: stages sum to {s:.3f} ms of total {total:.3f} ms: {t}"


def check_newton(stats):
    n = stats["newton"]
    hist = {int(k): v for k, v in n["iteration_histogram"].items()}
    outcomes = (n["converged"] + n["trimmed"] + n["diverged"] + n["singular"] + n["max_iterations"]
                + n["left_domain"] + n["behind_eye"])
    assert sum(hist.values()) == n["solves"] == outcomes, n
    assert all(0 <= k <= n["iteration_limit"] for k in hist), n
    # Unconverged after iteration_limit steps: counted in the histogram's last key.
    assert n["max_iterations"] <= hist.get(n["iteration_limit"], 0), n
    steps = sum(k * v for k, v in hist.items())
    assert abs(n["mean_iterations"] - (steps / n["solves"] if n["solves"] else 0)) < 1e-9, n
    r = stats["rescue"]
    assert r["neighbour"] + r["silhouette"] + r["general"] + r["trim_tolerance"] == n["fallback"], (n, r)
    assert n["converged"] + n["fallback"] == stats["pixels_hit"], (n, stats["pixels_hit"])
    cam = stats["camera"]
    size = "fov_deg" if cam["projection"] == "perspective" else "ortho_height"
    other = "ortho_height" if size == "fov_deg" else "fov_deg"
    assert size in cam and other not in cam, cam


def unique_screw():
    # A trailing newline count no other request uses: the first render is a miss.
    return SCREW.read_bytes() + b"\n" * (3 + (os.getpid() * 7 + int(time.time())) % 997)


def render(url, data, options, accept_json):
    return requests.post(url + "/v1/renders", files={"file": ("screw.step", data),
                                                     "options": (None, json.dumps(options))},
                         headers=JSON if accept_json else {}, timeout=TIMEOUT)


def test_render_stages_sum_to_total(url):
    data = unique_screw()
    opts = {"width": 160, "height": 120}
    first = render(url, data, opts, accept_json=True)  # an import: every stage runs
    assert first.status_code == 200, first.text[:300]
    validate(first.json(), "RenderResponse")
    stats = first.json()["statistics"]
    assert stats["cache"] == "miss"
    t = stats["timings_ms"]
    check_adds_up(t, RENDER_STAGES, "render JSON (miss)")
    for stage in ("isolation", "read", "nurbs_convert", "mesh", "transfer", "prepare"):
        assert t[stage] > 0, (stage, t)
    check_adds_up(server_timing(first), RENDER_STAGES, "render JSON (miss), Server-Timing")
    check_newton(stats)

    cached = render(url, data, opts, accept_json=True)  # the cached scene: no import stages
    stats = cached.json()["statistics"]
    assert stats["cache"] == "hit"
    for stage in ("prescan", "isolation", "read", "nurbs_convert", "mesh", "transfer", "prepare"):
        assert stats["timings_ms"][stage] == 0, (stage, stats["timings_ms"])
    check_adds_up(stats["timings_ms"], RENDER_STAGES, "render JSON (hit)")
    check_adds_up(server_timing(cached), RENDER_STAGES, "render JSON (hit), Server-Timing")
    check_newton(stats)

    image = render(url, data, opts, accept_json=False)  # an image answer: its timings are the header
    assert image.status_code == 200 and image.headers["Content-Type"] == "image/png"
    check_adds_up(server_timing(image), RENDER_STAGES, "render PNG (hit), Server-Timing")


def test_render_with_every_pass_adds_up(url):
    opts = {"width": 128, "height": 96, "antialias": 4, "edges": True, "shadows": True,
            "camera": {"projection": "orthographic", "view": "front"}}
    r = render(url, SCREW.read_bytes(), opts, accept_json=True)
    assert r.status_code == 200, r.text[:300]
    validate(r.json(), "RenderResponse")
    stats = r.json()["statistics"]
    for stage in ("antialias", "edges", "shadow_map"):
        assert stats["timings_ms"][stage] > 0, stage
    check_adds_up(stats["timings_ms"], RENDER_STAGES, "render with every pass")
    check_newton(stats)


def test_conversion_stages_sum_to_total(url):
    data = unique_screw()
    for fmt, source in (("stl", data), ("step", data), ("step", BEARING.read_bytes())):
        j = requests.post(url + "/v1/conversions", files={"file": ("in.cad", source), "format": (None, fmt)},
                          headers=JSON, timeout=TIMEOUT)
        assert j.status_code == 200, j.text[:300]
        body = j.json()
        validate(body, "ConversionResponse")
        t = body["timings_ms"]
        check_adds_up(t, CONVERSION_STAGES, f"conversion to {fmt}, JSON")
        check_adds_up(server_timing(j), CONVERSION_STAGES, f"conversion to {fmt}, JSON answer's Server-Timing")
        assert t["isolation"] > 0 and t["read"] > 0 and t["write"] > 0
        # verify: STEP read back and compared; STL measured against the exact faces (fidelity).
        assert (t["mesh"] > 0) == (fmt == "stl") and t["verify"] > 0, t
        f = requests.post(url + "/v1/conversions", files={"file": ("in.cad", source), "format": (None, fmt)},
                          timeout=TIMEOUT)
        assert f.status_code == 200
        check_adds_up(server_timing(f), CONVERSION_STAGES, f"conversion to {fmt}, file answer's Server-Timing")


def test_job_render_statistics_add_up(url):
    """A job's render runs the service's render code: its statistics add up the
    same way (ending with the statistics: a job has no HTTP answer to build);
    its conversions' reports too (STEP with its read-back check, and STL)."""
    spec = {"outputs": [{"file": 0, "type": "render", "options": {"width": 96, "height": 72}},
                        {"file": 0, "type": "conversion", "format": "step"},
                        {"file": 0, "type": "conversion", "format": "stl"}]}
    parts = [("file", ("screw.step", unique_screw(), "application/octet-stream")),
             ("job", (None, json.dumps(spec), "application/json"))]
    r = requests.post(url + "/v1/jobs", files=parts, timeout=TIMEOUT)
    assert r.status_code == 202, r.text[:300]
    job_url = url + r.headers["Location"]
    deadline = time.monotonic() + 90
    while True:
        job = requests.get(job_url, timeout=TIMEOUT).json()
        if job["state"] in ("succeeded", "failed"):
            break
        assert time.monotonic() < deadline, json.dumps(job)[:800]
        time.sleep(0.1)
    validate(job, "Job")
    assert job["state"] == "succeeded", json.dumps(job)[:800]
    stats = job["outputs"][0]["statistics"]
    check_adds_up(stats["timings_ms"], RENDER_STAGES, "job render")
    assert stats["timings_ms"]["response"] == 0
    check_newton(stats)
    for out in job["outputs"][1:]:
        t = out["report"]["timings_ms"]
        check_adds_up(t, CONVERSION_STAGES, f"job conversion to {out['format']}")
        assert t["isolation"] > 0 and t["write"] > 0, t
        assert t["upload"] == 0, t  # the input is on disk
        # The whole file is claimed in one run (SQLite, and PostgreSQL since it claims a file's outputs
        # together): its one read served the render's import first; it is the read's cost, not this output's.
        read = out["report"]["read"]
        assert read["read_ms"] > 0, read
        assert t["read"] == 0 and read["served"] == 3, (t, read)
