"""Batch jobs (/v1/jobs): several files with render and conversion outputs run
to completion, artifacts download and decode (images) or re-import with the
same face count (STEP/IGES); paging; 404s and traversal; every validation
error before 202; DELETE of a queued and a running job; the job queue bound;
retention; and recovery after the service is killed (SIGKILL) under a job."""
import http.client
import json
import os
import pathlib
import random
import signal
import struct
import subprocess
import time
import urllib.parse
import zlib


import pytest
import requests

from conftest import (SLOW_RENDER, BEARING, MODELS, SCREW, TIMEOUT, check_problem, healthy, post_raw, sqlite_only,
                      validate)

# Inputs: a large-ish IGES and a small STEP from ../shared/models, else OCCT's own data files.
if MODELS.is_dir():
    IGES_FILE = MODELS / "iges" / "bearing.iges"
    STEP_FILE = MODELS / "step" / "bug3883_xr2-ct-214_bolt.stp"
else:
    IGES_FILE, STEP_FILE = BEARING, SCREW
TRUNCATED_STEP = SCREW.read_bytes()[:1500]  # a STEP header, then nothing readable


def test_models_present_or_skipped_visibly():
    if not MODELS.is_dir():
        pytest.skip(f"{MODELS} is absent: jobs use /usr/share/opencascade/data files instead")


# ---- helpers -------------------------------------------------------------------------------------------

def submit(base, files, spec):
    """POST /v1/jobs with `files` [(filename, bytes)] as `file` parts and `spec` as the `job` part."""
    parts = [("file", (name, data, "application/octet-stream")) for name, data in files]
    parts.append(("job", (None, spec if isinstance(spec, str) else json.dumps(spec), "application/json")))
    return requests.post(base + "/v1/jobs", files=parts, timeout=TIMEOUT)


def accepted(resp):
    assert resp.status_code == 202, resp.text[:400]
    job = resp.json()
    validate(job, "Job")
    assert resp.headers["Location"] == f"/v1/jobs/{job['id']}" == job["url"]
    assert job["state"] in ("queued", "running")
    return job


def get_job(base, job_id):
    r = requests.get(f"{base}/v1/jobs/{job_id}", timeout=TIMEOUT)
    assert r.status_code == 200, r.text[:300]
    job = r.json()
    validate(job, "Job")
    return job


def wait_for(base, job_id, pred, timeout=90, what="condition"):
    deadline = time.monotonic() + timeout
    while True:
        job = get_job(base, job_id)
        if pred(job):
            return job
        assert time.monotonic() < deadline, f"job never reached {what}: {json.dumps(job)[:800]}"
        time.sleep(0.1)


def wait_finished(base, job_id, timeout=90):
    return wait_for(base, job_id, lambda j: j["state"] in ("succeeded", "failed"), timeout, "a finished state")


def wait_gone(base, job_id, timeout=30):
    deadline = time.monotonic() + timeout
    while requests.get(f"{base}/v1/jobs/{job_id}", timeout=TIMEOUT).status_code != 404:
        assert time.monotonic() < deadline, "the job was never removed"
        time.sleep(0.1)


def download(base, output):
    art = output["artifact"]
    r = requests.get(base + art["url"], timeout=TIMEOUT)
    assert r.status_code == 200, r.text[:300]
    assert r.headers["Content-Type"] == art["content_type"]
    assert r.headers["Content-Disposition"] == f'attachment; filename="{art["name"]}"'
    assert len(r.content) == art["bytes"] > 0
    return r.content


def png_pixels(data):
    """(width, height, channels, rows) of a non-interlaced 8-bit PNG, rows unfiltered
    (PNG specification, section 9: filter types 0-4), each a bytes of width * channels."""
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    pos, idat, ihdr = 8, b"", None
    while pos < len(data):
        length, ctype = struct.unpack(">I4s", data[pos:pos + 8])
        body = data[pos + 8:pos + 8 + length]
        if ctype == b"IHDR":
            ihdr = struct.unpack(">IIBBBBB", body)
        elif ctype == b"IDAT":
            idat += body
        pos += 12 + length
    width, height, depth, color, _, _, interlace = ihdr
    assert depth == 8 and interlace == 0
    ch = {0: 1, 2: 3, 4: 2, 6: 4}[color]
    raw, stride, rows, prev = zlib.decompress(idat), width * ch, [], bytearray(width * ch)
    for y in range(height):
        f, line = raw[y * (stride + 1)], bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        for i in range(stride):
            a = line[i - ch] if i >= ch else 0
            b, c = prev[i], prev[i - ch] if i >= ch else 0
            if f == 1:
                line[i] = (line[i] + a) & 255
            elif f == 2:
                line[i] = (line[i] + b) & 255
            elif f == 3:
                line[i] = (line[i] + (a + b) // 2) & 255
            elif f == 4:
                pa, pb, pc = abs(b - c), abs(a - c), abs(a + b - 2 * c)
                line[i] = (line[i] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
        rows.append(bytes(line))
        prev = line
    return width, height, ch, rows


def png_size(data):
    """Decodes a non-interlaced 8-bit PNG far enough to prove it whole: chunk CRCs, IHDR, and the
    inflated IDAT stream of exactly height rows of (filter byte + width * channels) bytes."""
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    pos, idat, ihdr = 8, b"", None
    while pos < len(data):
        length, ctype = struct.unpack(">I4s", data[pos:pos + 8])
        body = data[pos + 8:pos + 8 + length]
        (crc,) = struct.unpack(">I", data[pos + 8 + length:pos + 12 + length])
        assert zlib.crc32(ctype + body) == crc, ctype
        if ctype == b"IHDR":
            ihdr = struct.unpack(">IIBBBBB", body)
        elif ctype == b"IDAT":
            idat += body
        pos += 12 + length
        if ctype == b"IEND":
            break
    width, height, depth, color, _, _, interlace = ihdr
    assert depth == 8 and interlace == 0
    channels = {0: 1, 2: 3, 4: 2, 6: 4}[color]
    assert len(zlib.decompress(idat)) == height * (1 + width * channels)
    return width, height


def check_artifact(base, output):
    """Downloads a PNG render, STEP or IGES conversion artifact and checks it whole: a PNG of the
    requested size inflated row by row (a half-written file fails), a STEP or IGES file with its end."""
    data = download(base, output)
    if output["type"] == "render":
        assert png_size(data) == (output["options"]["width"], output["options"]["height"])
    elif output["format"] in ("step", "stp"):
        assert data.startswith(b"ISO-10303-21;") and b"END-ISO-10303-21;" in data[-200:]
    else:
        assert data[72:73] == b"S" and data.rstrip()[-8:-7] == b"T", data[-80:]  # IGES: Start ... Terminate


def exr_size(data):
    """OpenEXR magic, then the header's dataWindow attribute (box2i)."""
    assert data[:4] == b"\x76\x2f\x31\x01"
    pos = 8
    while data[pos] != 0:
        name_end = data.index(b"\0", pos)
        type_end = data.index(b"\0", name_end + 1)
        name = data[pos:name_end]
        (size,) = struct.unpack("<i", data[type_end + 1:type_end + 5])
        value = data[type_end + 5:type_end + 5 + size]
        if name == b"dataWindow":
            xmin, ymin, xmax, ymax = struct.unpack("<iiii", value)
            return xmax - xmin + 1, ymax - ymin + 1
        pos = type_end + 5 + size
    raise AssertionError("no dataWindow in the EXR header")


def face_count(path):
    out = subprocess.run([os.environ["NURBSRT_BIN"], "info", "--json", str(path)], capture_output=True,
                         timeout=120, check=True)
    return json.loads(out.stdout)["faces"]


def raw_get(base, path):
    """A GET with the path sent exactly as written (no client-side normalisation of ../)."""
    u = urllib.parse.urlparse(base)
    conn = http.client.HTTPConnection(u.hostname, u.port, timeout=30)
    conn.request("GET", path)
    r = conn.getresponse()
    body = r.read()
    conn.close()
    return r.status, r.getheader("Content-Type", ""), body


# ---- a complete job ------------------------------------------------------------------------------------

def test_job_with_several_files_and_outputs(url, tmp_path):
    iges, step = IGES_FILE.read_bytes(), STEP_FILE.read_bytes()
    spec = {"outputs": [
        {"file": 0, "type": "render", "options": {"width": 96, "height": 72, "view": "front"}},
        {"file": STEP_FILE.name, "type": "render", "options": {"width": 64, "height": 48, "format": "exr"}},
        {"file": 0, "type": "conversion", "format": "step"},
        {"file": 1, "type": "conversion", "format": "iges"},
    ]}
    t0 = time.monotonic()
    job = accepted(submit(url, [(IGES_FILE.name, iges), (STEP_FILE.name, step)], spec))
    assert [f["format"] for f in job["files"]] == ["IGES", "STEP"]
    assert [f["bytes"] for f in job["files"]] == [len(iges), len(step)]
    assert [o["state"] for o in job["outputs"]] == ["queued"] * 4
    job = wait_finished(url, job["id"])
    wall_ms = (time.monotonic() - t0) * 1000
    assert job["state"] == "succeeded", json.dumps(job)[:1000]
    assert "error" not in job and job["progress"] == 1 and job["attempts"] == 1
    assert job["created_at"] <= job["started_at"] <= job["finished_at"]
    assert 0 <= job["timings_ms"]["run"] <= wall_ms
    names = [o["artifact"]["name"] for o in job["outputs"]]
    assert names == ["0-render-0.png", "1-render-1.exr", "0-conversion-2.step", "1-conversion-3.igs"]
    for o in job["outputs"]:
        assert o["state"] == "succeeded" and o["progress"] == 1
        assert o["started_at"] <= o["finished_at"] and o["duration_ms"] >= 0

    png, exr = download(url, job["outputs"][0]), download(url, job["outputs"][1])
    assert png_size(png) == (96, 72)
    assert exr_size(exr) == (64, 48)
    stats = job["outputs"][0]["statistics"]
    assert (stats["width"], stats["height"], stats["camera"]["projection"]) == (96, 72, "orthographic")  # a named view
    assert stats["pixels_hit"] > 0

    # The conversions re-import with the faces of their inputs.
    (tmp_path / "in.igs").write_bytes(iges)
    (tmp_path / "in.stp").write_bytes(step)
    (tmp_path / "out.step").write_bytes(download(url, job["outputs"][2]))
    (tmp_path / "out.igs").write_bytes(download(url, job["outputs"][3]))
    assert (tmp_path / "out.step").read_bytes().startswith(b"ISO-10303-21;")
    for src, out, output in (("in.igs", "out.step", 2), ("in.stp", "out.igs", 3)):
        faces = face_count(tmp_path / src)
        assert face_count(tmp_path / out) == faces > 0
        assert job["outputs"][output]["report"]["faces"] == faces

    m = requests.get(url + "/metrics", timeout=TIMEOUT).text
    assert 'nurbsrt_jobs{state="succeeded"}' in m
    assert 'nurbsrt_jobs_finished_total{result="succeeded"}' in m
    assert 'nurbsrt_jobs_finished_total{result="succeeded"} 0' not in m


def test_render_output_with_separate_views_is_an_artifact_per_view(url):
    """A job's render with views and layout separate: an artifact per view, `<output>.<view>.png`, listed with
    its view and counted in the job's statistics (test_jobs_formats.py: downloadable while the job runs)."""
    job = accepted(submit(url, [("screw.step", SCREW.read_bytes())], {"outputs": [
        {"file": 0, "type": "render",
         "options": {"width": 96, "height": 72, "views": ["front", "iso"], "layout": "separate"}}]}))
    job = wait_finished(url, job["id"])
    assert job["state"] == "succeeded", json.dumps(job)[:800]
    out = job["outputs"][0]
    files = out["artifacts"]
    assert [(a["name"], a["view"], a["content_type"]) for a in files] == [
        ("0-render-0.front.png", "front", "image/png"), ("0-render-0.iso.png", "iso", "image/png")]
    assert out["artifact"] == files[0] and out["format"] == "png"
    assert all(png_size(download(url, {"artifact": a})) == (96, 72) for a in files)
    assert out["statistics"]["artifacts"] == [{"name": a["name"], "bytes": a["bytes"]} for a in files]
    assert job["statistics"]["artifacts"] == 2
    assert job["statistics"]["artifact_bytes"] == sum(a["bytes"] for a in files)


def test_unreadable_cad_is_a_failed_output(url):
    spec = {"outputs": [{"file": 0, "type": "conversion", "format": "iges"},
                        {"file": 1, "type": "render", "options": {"width": 32, "height": 32}}]}
    job = accepted(submit(url, [("cut.step", TRUNCATED_STEP), ("screw.step", SCREW.read_bytes())], spec))
    job = wait_finished(url, job["id"])
    assert job["state"] == "failed"
    bad, good = job["outputs"]
    assert bad["state"] == "failed" and bad["error"]["code"] == "unreadable_file" and bad["error"]["message"]
    assert "/jobs/" not in bad["error"]["message"]  # no server paths in messages
    assert "artifact" not in bad
    assert good["state"] == "succeeded"
    assert png_size(download(url, good)) == (32, 32)  # the other output still has its artifact
    assert job["error"]["code"] == "unreadable_file" and "1 of 2 outputs failed" in job["error"]["message"]
    status, _, _ = raw_get(url, f"/v1/jobs/{job['id']}/artifacts/{'0-conversion-0.igs'}")
    assert status == 404


def test_each_file_is_read_once_for_all_its_outputs(url):
    """A file's render, STL and glb come from one read of the file (one isolated child imports it and writes
    the conversions); a file that cannot be read fails its own outputs, with the read's error, and no other."""
    per_file = [{"type": "render", "options": {"width": 48, "height": 36}},
                {"type": "conversion", "format": "stl"}, {"type": "conversion", "format": "glb"}]
    spec = {"outputs": [{"file": f, **o} for f in (0, 1, 2) for o in per_file]}
    pad = b"\n" * random.randrange(3, 1000)  # bytes no other test sends: their scenes are not cached yet
    files = [("screw.step", SCREW.read_bytes() + pad), ("cut.step", TRUNCATED_STEP),
             ("bearing.iges", BEARING.read_bytes() + pad)]
    job = wait_finished(url, accepted(submit(url, files, spec))["id"])
    assert job["state"] == "failed"
    outs = job["outputs"]
    assert [o["state"] for o in outs] == ["succeeded"] * 3 + ["failed"] * 3 + ["succeeded"] * 3
    assert {o["error"]["code"] for o in outs[3:6]} == {"unreadable_file"}
    assert len({o["error"]["message"] for o in outs[3:6]}) == 1  # the one read's error, for each
    reads = [(o.get("statistics") or o.get("report"))["read"] for o in outs if o["state"] == "succeeded"]
    assert [r["file"] for r in reads] == [0, 0, 0, 2, 2, 2]
    stats = job["statistics"]
    assert stats["outputs"] == 9 and stats["succeeded"] == 6 and stats["failed"] == 3
    assert stats["artifact_bytes"] == sum(o["artifact"]["bytes"] for o in outs if o["state"] == "succeeded")
    # With either store (PostgreSQL claims a file's outputs together).
    assert stats["reads"] == 2
    assert len({r["id"] for r in reads[:3]}) == 1 and len({r["id"] for r in reads[3:]}) == 1
    assert all(r["served"] == 3 and r["read_ms"] > 0 for r in reads)
    # The job's own read made the renders' scenes: not from the cache.
    assert [outs[k]["statistics"]["cache"] for k in (0, 6)] == ["miss", "miss"]
    assert png_size(download(url, outs[0])) == (48, 36)
    assert download(url, outs[7])[80:84] != b""  # STL: 80-byte header, then the triangle count
    assert download(url, outs[8])[:4] == b"glTF"
    # The same files again, made anew (force: no artifact reuse): the renders find their scenes cached (no read
    # for them); the conversions read.
    again = wait_finished(url, accepted(submit(url, files, {**spec, "force": True}))["id"])
    cached = [again["outputs"][k] for k in (0, 6)]
    assert all(o["state"] == "succeeded" and o["statistics"]["cache"] == "hit" for o in cached)
    assert all("read" not in o["statistics"] for o in cached)
    assert [o["report"]["read"]["served"] for o in again["outputs"] if o["state"] == "succeeded" and o["type"] ==
            "conversion"] == [2] * 4


def test_a_job_and_a_client_rendering_one_new_file_import_it_once(url):
    """A job's file and a client's render of the same new bytes at the same time: the scene cache's single
    flight imports it once for both, whoever comes first; the other finds it cached or waits for it."""
    import concurrent.futures
    data = BEARING.read_bytes() + b"\n" * random.randrange(1000, 5000)  # bytes no other test sends
    spec = {"outputs": [{"file": 0, "type": "render", "options": {"width": 40, "height": 30}}]}
    with concurrent.futures.ThreadPoolExecutor(1) as pool:
        client = pool.submit(post_raw, url, "/v1/renders", data, {"width": 40, "height": 30},
                             {"Accept": "application/json"})
        job = accepted(submit(url, [("bearing.iges", data)], spec))
        render = client.result()
    job = wait_finished(url, job["id"])
    assert render.status_code == 200 and job["state"] == "succeeded", (render.text[:300], json.dumps(job)[:600])
    caches = sorted([render.json()["statistics"]["cache"], job["outputs"][0]["statistics"]["cache"]])
    assert caches == ["hit", "miss"], caches
    assert job["statistics"]["reads"] == (1 if job["outputs"][0]["statistics"]["cache"] == "miss" else 0)


def test_an_output_made_before_is_reused_unless_forced(url):
    """An output whose file bytes, type and options match an artifact an earlier job made is served from that
    artifact (no read, no render or conversion; `reused: true`); other options, or `force: true`, make it anew.
    The reused artifact outlives the job that made it."""
    data = SCREW.read_bytes() + b"\n" * random.randrange(5000, 9000)  # bytes no other test sends
    spec = {"outputs": [{"file": 0, "type": "render", "options": {"width": 40, "height": 30}},
                        {"file": 0, "type": "conversion", "format": "stl"}]}
    first = wait_finished(url, accepted(submit(url, [("screw.step", data)], spec))["id"])
    assert first["state"] == "succeeded", json.dumps(first)[:600]
    assert first["statistics"]["reused"] == 0 and first["statistics"]["reads"] == 1
    assert not any((o.get("statistics") or o["report"]).get("reused") for o in first["outputs"])

    again = wait_finished(url, accepted(submit(url, [("again.step", data)], spec))["id"])
    assert again["state"] == "succeeded", json.dumps(again)[:600]
    assert again["statistics"]["reused"] == 2 and again["statistics"]["reads"] == 0
    render, stl = again["outputs"]
    assert render["statistics"]["reused"] is True and stl["report"]["reused"] is True
    assert "read" not in render["statistics"] and "read" not in stl["report"]
    assert stl["report"]["output_format"] == "STL"  # the report of the run that made it
    for a, b in zip(first["outputs"], again["outputs"]):
        assert download(url, a) == download(url, b)
        assert a["artifact"]["bytes"] == b["artifact"]["bytes"]

    # Other options of the same file: made anew; force: made anew although the same were made before.
    other = {"outputs": [{"file": 0, "type": "render", "options": {"width": 41, "height": 30}}]}
    changed = wait_finished(url, accepted(submit(url, [("screw.step", data)], other))["id"])
    assert changed["statistics"]["reused"] == 0 and "reused" not in changed["outputs"][0]["statistics"]
    forced = wait_finished(url, accepted(submit(url, [("screw.step", data)], {**spec, "force": True}))["id"])
    assert forced["state"] == "succeeded" and forced["statistics"]["reused"] == 0
    assert forced["statistics"]["reads"] == 1

    # The job that made them deleted: the artifact is still served to a new job, and the last one keeps its own.
    assert requests.delete(f"{url}/v1/jobs/{first['id']}", timeout=TIMEOUT).status_code in (200, 204)
    third = wait_finished(url, accepted(submit(url, [("third.step", data)], spec))["id"])
    assert third["statistics"]["reused"] == 2
    assert png_size(download(url, third["outputs"][0])) == (40, 30)
    assert download(url, again["outputs"][1]) == download(url, third["outputs"][1])
    check_problem(submit(url, [("screw.step", data)], {**spec, "force": "yes"}), 400)


# ---- listing --------------------------------------------------------------------------------------------

def test_listing_pages_and_filters(url):
    ids = [accepted(submit(url, [("s.step", SCREW.read_bytes())],
                           {"outputs": [{"file": 0, "type": "conversion", "format": "iges"}]}))["id"]
           for _ in range(3)]

    def walk(order, limit=2, state=None):
        seen, cursor, pages = [], None, 0
        while True:
            params = {"limit": limit, "order": order}
            if cursor:
                params["cursor"] = cursor
            if state:
                params["state"] = state
            r = requests.get(url + "/v1/jobs", params=params, timeout=TIMEOUT)
            assert r.status_code == 200, r.text[:300]
            body = r.json()
            validate(body, "JobList")
            assert len(body["jobs"]) <= limit
            seen += [j["id"] for j in body["jobs"]]
            for j in body["jobs"]:
                assert state is None or j["state"] == state
            pages += 1
            cursor = body["next_cursor"]
            if cursor is None:
                return seen, pages
            assert pages < 500

    newest, pages = walk("newest")
    assert pages >= 2 and len(newest) == len(set(newest))
    assert [i for i in newest if i in ids] == ids[::-1]  # newest first
    oldest, _ = walk("oldest", limit=3)
    assert oldest == newest[::-1]
    assert newest[:3] == ids[::-1]  # nothing newer was submitted meanwhile
    for j in ids:
        wait_finished(url, j)
    succeeded, _ = walk("newest", limit=5, state="succeeded")
    assert set(ids) <= set(succeeded)
    queued, _ = walk("newest", state="queued")
    assert not set(ids) & set(queued)

    first = requests.get(url + "/v1/jobs", params={"limit": 1}, timeout=TIMEOUT).json()
    assert first["jobs"][0]["id"] == ids[-1] and first["next_cursor"]
    for params in ({"limit": 0}, {"limit": 101}, {"limit": "x"}, {"order": "random"}, {"state": "done"},
                   {"cursor": "zz"}, {"cursor": first["next_cursor"], "order": "oldest"}, {"page": 2}):
        check_problem(requests.get(url + "/v1/jobs", params=params, timeout=TIMEOUT), 400, "invalid_argument")


# ---- not found, traversal --------------------------------------------------------------------------------

def test_not_found_and_traversal(url):
    job = accepted(submit(url, [("s.step", SCREW.read_bytes())],
                          {"outputs": [{"file": 0, "type": "render", "options": {"width": 40, "height": 30}}]}))
    job = wait_finished(url, job["id"])
    assert job["state"] == "succeeded"
    base = f"/v1/jobs/{job['id']}"
    assert raw_get(url, base + "/artifacts/0-render-0.png")[0] == 200
    for path in ("/v1/jobs/" + "0" * 32, "/v1/jobs/nope", "/v1/jobs/..%2F..%2Fjobs.db",
                 base + "/artifacts/0-render-1.png",   # a valid name, not this job's
                 base + "/artifacts/input-0.cad",      # exists on disk, but is no artifact
                 base + "/artifacts/..%2Finput-0.cad", base + "/artifacts/..%2F..%2F..%2Fjobs.db",
                 base + "/artifacts/%2e%2e%2f%2e%2e%2fjobs.db", base + "/artifacts/../../../jobs.db",
                 base + "/artifacts/0-render-0.png%00.txt", "/v1/jobs/" + "0" * 32 + "/artifacts/0-render-0.png"):
        status, ctype, body = raw_get(url, path)
        assert status in (400, 404), (path, status)
        assert ctype.startswith("application/problem+json"), (path, ctype)
        validate(json.loads(body), "Problem")
    check_problem(requests.delete(url + "/v1/jobs/" + "f" * 32, timeout=TIMEOUT), 404, "not_found")
    # DELETE of a finished job removes it and its artifacts.
    r = requests.delete(url + base, timeout=TIMEOUT)
    assert r.status_code == 204
    check_problem(requests.get(url + base, timeout=TIMEOUT), 404, "not_found")
    assert raw_get(url, base + "/artifacts/0-render-0.png")[0] == 404
    data_dir = os.environ.get("NURBSRT_DATA_DIR")
    if data_dir:
        assert not (pathlib.Path(data_dir) / "jobs" / job["id"]).exists()


# ---- validation before 202 -------------------------------------------------------------------------------

def test_validation_errors_before_202(url):
    def count():
        return sum(1 for _ in requests.get(url + "/v1/jobs", params={"limit": 100}, timeout=TIMEOUT).json()["jobs"])

    before = count()
    step = [("s.step", SCREW.read_bytes())]
    conv = {"outputs": [{"file": 0, "type": "conversion", "format": "iges"}]}
    render = lambda **o: {"outputs": [{"file": 0, "type": "render", "options": o}]}  # noqa: E731
    cases = [
        (submit(url, step, "not json"), 400),
        (submit(url, step, {"outputs": []}), 400),
        (submit(url, step, {"outputs": [{"file": 0, "type": "render"}], "extra": 1}), 400),
        (submit(url, step, {"outputs": [{"file": 1, "type": "render"}]}), 400),
        (submit(url, step, {"outputs": [{"file": "other.step", "type": "render"}]}), 400),
        (submit(url, step, {"outputs": [{"file": 0, "type": "thumbnail"}]}), 400),
        (submit(url, step, {"outputs": [{"file": 0, "type": "conversion"}]}), 400),
        (submit(url, step, {"outputs": [{"file": 0, "type": "conversion", "format": "dwg"}]}), 400),
        (submit(url, step, {"outputs": [{"file": 0, "type": "conversion", "format": "iges", "width": 3}]}), 400),
        (submit(url, step, render(width=-1)), 400),
        (submit(url, step, render(format="gif")), 400),
        (submit(url, step, render(view="sideways")), 400),
        (submit(url, step, render(width=5000, height=10)), 422),     # over --max-dimension 4096
        (submit(url, step, render(width=4000, height=4000)), 422),   # over --max-pixels 4000000
        (submit(url, step + step, conv), 400),                        # file 1 has no outputs
        (submit(url, [("a.step", SCREW.read_bytes()), ("a.step", SCREW.read_bytes())],
                {"outputs": [{"file": "a.step", "type": "render"}, {"file": 1, "type": "render"}]}), 400),
        (submit(url, [("e.step", b"")], conv), 400),
        (submit(url, [("hello.step", b"hello world")], conv), 415),
        (submit(url, [], conv), 400),
        (requests.post(url + "/v1/jobs", files={"file": ("s.step", SCREW.read_bytes())}, timeout=TIMEOUT), 400),
        (requests.post(url + "/v1/jobs", data=SCREW.read_bytes(),
                       headers={"Content-Type": "application/octet-stream"}, timeout=TIMEOUT), 415),
        (submit(url, [("big.step", b"ISO-10303-21;\n" + b" " * (5 << 20))], conv), 413),  # over --max-upload-mb 4
    ]
    for i, (resp, status) in enumerate(cases):
        body = check_problem(resp, status)
        assert body["detail"], i
    assert count() == before  # none of them created a job


def test_job_limits_and_queue_bound(own_server):
    s = own_server(args=["--max-job-files", "2", "--max-job-outputs", "3", "--max-queued-jobs", "1",
                         "--workers", "1", "--job-runners", "1", "--render-threads", "1", "--queue-timeout", "0.5"])
    step = SCREW.read_bytes()
    render = {"file": 0, "type": "render", "options": {"width": 16, "height": 16}}
    check_problem(submit(s.url, [("a.step", step)] * 3, {"outputs": [dict(render, file=i) for i in range(3)]}),
                  422, "limit_exceeded")
    check_problem(submit(s.url, [("a.step", step)], {"outputs": [render] * 4}), 422, "limit_exceeded")
    # One slow job runs, one waits: the next is turned away with Retry-After.
    slow = {"outputs": [{"file": 0, "type": "render", "options": SLOW_RENDER}]}
    running = accepted(submit(s.url, [("b.igs", BEARING.read_bytes())], slow))
    wait_for(s.url, running["id"], lambda j: j["outputs"][0]["state"] == "running", what="running")
    # The job's render holds memory, not the only import/conversion worker: a small synchronous
    # render (its import included) is not stuck behind it and shares the cores.
    deadline = time.monotonic() + 60  # "running" starts with the import; then the render is admitted
    while "nurbsrt_renders_active 1\n" not in requests.get(s.url + "/metrics", timeout=TIMEOUT).text:
        assert time.monotonic() < deadline, "the job's render never started"
        time.sleep(0.05)
    r = requests.post(s.url + "/v1/renders", params={"width": 16, "height": 16}, data=step,
                      headers={"Content-Type": "application/octet-stream"}, timeout=TIMEOUT)
    assert r.status_code == 200, r.text[:300]
    assert get_job(s.url, running["id"])["outputs"][0]["state"] == "running"
    queued = accepted(submit(s.url, [("a.step", step)], {"outputs": [render]}))
    r = submit(s.url, [("a.step", step)], {"outputs": [render]})
    check_problem(r, 503, "overloaded")
    assert int(r.headers["Retry-After"]) >= 1
    # DELETE of the queued job: gone at once, with its files.
    assert requests.delete(f"{s.url}/v1/jobs/{queued['id']}", timeout=TIMEOUT).status_code == 204
    check_problem(requests.get(f"{s.url}/v1/jobs/{queued['id']}", timeout=TIMEOUT), 404)
    assert not (s.data_dir / "jobs" / queued["id"]).exists()
    requests.delete(f"{s.url}/v1/jobs/{running['id']}", timeout=TIMEOUT)


# ---- results as they come ---------------------------------------------------------------------------------

def test_an_artifact_downloads_as_soon_as_its_output_is_done(own_server):
    """While a job still runs (a slow render), its finished output is listed with its URL and downloads, and the
    job's statistics count the outputs done and their bytes so far."""
    s = own_server(args=["--workers", "1", "--job-runners", "1", "--render-threads", "1"])
    spec = {"outputs": [{"file": 0, "type": "conversion", "format": "stl"},
                        {"file": 0, "type": "render", "options": SLOW_RENDER}], "force": True}
    job = accepted(submit(s.url, [("s.step", SCREW.read_bytes())], spec))
    job = wait_for(s.url, job["id"], lambda j: j["outputs"][0]["state"] == "succeeded",
                   what="the conversion done")
    assert job["state"] == "running" and job["outputs"][1]["state"] in ("queued", "running"), json.dumps(job)[:600]
    stl = job["outputs"][0]
    data = download(s.url, stl)
    assert len(data) == 84 + 50 * struct.unpack("<I", data[80:84])[0]  # a whole binary STL
    stats = job["statistics"]
    assert (stats["outputs"], stats["succeeded"], stats["failed"]) == (2, 1, 0)
    assert stats["artifact_bytes"] == stl["artifact"]["bytes"] == len(data)
    assert 0.5 <= job["progress"] < 1
    # The render's artifact is not there yet: 404 naming its state.
    check_problem(requests.get(f"{s.url}/v1/jobs/{job['id']}/artifacts/0-render-1.png", timeout=TIMEOUT), 404)
    assert requests.delete(f"{s.url}/v1/jobs/{job['id']}", timeout=TIMEOUT).status_code == 202


# ---- DELETE of a running job -------------------------------------------------------------------------------

def test_delete_running_job(own_server):
    s = own_server(args=["--workers", "1", "--job-runners", "1", "--render-threads", "1"])
    spec = {"outputs": [{"file": 0, "type": "render", "options": SLOW_RENDER},
                        {"file": 0, "type": "conversion", "format": "step"}]}
    job = accepted(submit(s.url, [("b.igs", BEARING.read_bytes())], spec))
    job = wait_for(s.url, job["id"], lambda j: j["outputs"][0]["state"] == "running" and j["outputs"][0]["progress"] > 0,
                   what="a render with progress")
    assert 0 < job["outputs"][0]["progress"] < 1
    r = requests.delete(f"{s.url}/v1/jobs/{job['id']}", timeout=TIMEOUT)
    assert r.status_code == 202, r.text[:300]  # running: canceled now, removed once the render stops
    body = r.json()
    validate(body, "Job")
    assert body["state"] == "canceled" and body["error"]["code"] == "canceled"
    # The render is cut. Its file's conversion was written with the file's one read before the render began
    # (the runner claims a file's outputs together, with either store).
    assert body["outputs"][0]["state"] == "canceled"
    assert body["outputs"][1]["state"] == "succeeded"
    wait_gone(s.url, job["id"])
    check_problem(requests.get(f"{s.url}/v1/jobs/{job['id']}", timeout=TIMEOUT), 404)
    deadline = time.monotonic() + 10
    while (s.data_dir / "jobs" / job["id"]).exists():
        assert time.monotonic() < deadline, "the job's files were not removed"
        time.sleep(0.1)
    healthy(s.url)
    # The worker slot is free again: a synchronous render goes through.
    r = requests.post(s.url + "/v1/renders", params={"width": 32, "height": 32}, data=SCREW.read_bytes(),
                      headers={"Content-Type": "application/octet-stream"}, timeout=TIMEOUT)
    assert r.status_code == 200
    m = requests.get(s.url + "/metrics", timeout=TIMEOUT).text
    assert 'nurbsrt_jobs_finished_total{result="canceled"} 1' in m
    # Only that synchronous render completed: the job's render was stopped, not run to its end.
    assert 'nurbsrt_render_stage_seconds_count{stage="total"} 1\n' in m


# ---- retention ---------------------------------------------------------------------------------------------

def test_finished_jobs_expire(own_server):
    s = own_server(args=["--job-retention", "2"])
    job = accepted(submit(s.url, [("s.step", SCREW.read_bytes())],
                          {"outputs": [{"file": 0, "type": "conversion", "format": "iges"}]}))
    job = wait_finished(s.url, job["id"])
    assert job["state"] == "succeeded"
    download(s.url, job["outputs"][0])  # still there right after it finished
    wait_gone(s.url, job["id"], timeout=15)
    # The rows go first, then the directory (a crash between leaves an orphan directory, which the sweeps
    # remove, never a job whose files are gone): the directory follows within moments, not at the same instant.
    deadline = time.monotonic() + 5
    while (s.data_dir / "jobs" / job["id"]).exists():
        assert time.monotonic() < deadline, "the expired job's directory was not removed"
        time.sleep(0.05)


# ---- SIGKILL under a running job ---------------------------------------------------------------------------

SLOW_ARGS = ["--workers", "1", "--job-runners", "1", "--render-threads", "1"]
SLOW_SPEC = {"outputs": [{"file": 0, "type": "conversion", "format": "iges"},
                         {"file": 0, "type": "render", "options": SLOW_RENDER}]}


def kill_while_rendering(s, job_id, attempt):
    job = wait_for(s.url, job_id, lambda j: j["attempts"] == attempt and j["outputs"][1]["state"] == "running",
                   what=f"attempt {attempt} rendering")
    s.proc.kill()  # SIGKILL: no chance to put anything in order
    s.proc.wait(timeout=10)
    return job


def test_sigkill_then_restart_reruns_the_job(own_server, tmp_path):
    data = tmp_path / "data"
    s1 = own_server(args=SLOW_ARGS, data_dir=data)
    job = accepted(submit(s1.url, [("s.step", SCREW.read_bytes())], SLOW_SPEC))
    before = kill_while_rendering(s1, job["id"], 1)
    conversion = before["outputs"][0]
    assert conversion["state"] == "succeeded"

    s2 = own_server(args=SLOW_ARGS, data_dir=data)
    job = wait_finished(s2.url, job["id"])
    assert job["state"] == "succeeded", json.dumps(job)[:800]
    assert job["attempts"] == 2
    assert job["outputs"][0]["finished_at"] == conversion["finished_at"]  # kept, not converted again
    assert download(s2.url, job["outputs"][0])[72:73] == b"S"  # IGES: the first record is the Start section
    assert png_size(download(s2.url, job["outputs"][1])) == (SLOW_RENDER["width"], SLOW_RENDER["height"])


def test_twice_interrupted_job_fails_with_the_restart_reason(own_server, tmp_path):
    """An output cut short by a crash in each of its allowed runs (here 2) fails `interrupted`."""
    data = tmp_path / "data"
    args = [*SLOW_ARGS, "--max-output-attempts", "2"]
    s1 = own_server(args=args, data_dir=data)
    job = accepted(submit(s1.url, [("s.step", SCREW.read_bytes())], SLOW_SPEC))
    kill_while_rendering(s1, job["id"], 1)
    s2 = own_server(args=args, data_dir=data)
    kill_while_rendering(s2, job["id"], 2)
    s3 = own_server(args=args, data_dir=data)
    # SQLite: failed at once by the restart's recovery; PostgreSQL: once the lease has expired.
    job = wait_finished(s3.url, job["id"])
    assert job["state"] == "failed"
    assert job["error"]["code"] == "interrupted"
    assert "interrupted by a service restart" in job["error"]["message"]
    conv, rend = job["outputs"]
    assert conv["state"] == "succeeded"
    assert download(s3.url, conv)[72:73] == b"S"  # the finished output keeps its IGES artifact
    assert rend["state"] == "failed" and rend["error"]["code"] == "interrupted"
    healthy(s3.url)


@sqlite_only
def test_random_sigkills_fail_no_job(own_server, tmp_path):
    """24 jobs of 6 outputs, and the service SIGKILLed 14 times at random moments while they run, restarted
    each time on its data directory: every job succeeds, each output once, none lost. A crash counts only
    against the output it cut short (3 runs each by default), not against its queued or finished siblings: under
    one budget of 2 runs per job, 12 of 16 such jobs failed `interrupted`, outputs that never started included.
    (24 jobs and 640x480 renders: with each file read once for its 6 outputs, 16 jobs with 400x300 renders
    were done before the 14th kill.)
    Each kill comes at a random moment after the restarted service has finished at least one more output, as
    crashes independent of the work would: a service killed faster than it can finish anything fails an
    output under any budget, and that is not what this is about."""
    rng = random.Random(46)  # the kill moments vary the same way in every run
    data = tmp_path / "data"
    args = ["--workers", "1", "--job-runners", "1", "--render-threads", "1"]
    # force: 24 jobs of one file and one spec, each made anew (else all but the first reuse its artifacts).
    spec = {"outputs": [{"file": 0, "type": "render", "options": {"width": 640, "height": 480, "edges": True}},
                        {"file": 0, "type": "conversion", "format": "stl"}] * 3, "force": True}
    s = own_server(args=args, data_dir=data)
    ids = [accepted(submit(s.url, [("s.step", SCREW.read_bytes())], spec))["id"] for _ in range(24)]

    def finished_outputs():
        listed = requests.get(s.url + "/v1/jobs", params={"limit": 100}, timeout=TIMEOUT).json()["jobs"]
        return sum(o["state"] == "succeeded" for j in listed for o in j["outputs"])

    kills = 0
    while kills < 14:
        since = finished_outputs()
        deadline = time.monotonic() + 60
        while (done := finished_outputs()) == since and done < 144:
            assert time.monotonic() < deadline, "no output finished within 60 s of a restart"
            time.sleep(0.02)
        if done == 144:
            break  # all done before the kills ran out: the rest would test nothing
        time.sleep(rng.uniform(0.0, 0.4))
        s.proc.kill()
        s.proc.wait(timeout=10)
        kills += 1
        s = own_server(args=args, data_dir=data)
    jobs = [wait_finished(s.url, i, timeout=180) for i in ids]
    runs = f"{kills} kills; jobs run {sum(j['attempts'] for j in jobs)} times in all"
    print(runs)
    assert kills == 14, f"only {kills} kills happened while jobs ran: the test lost its point ({runs})"
    listed = requests.get(s.url + "/v1/jobs", params={"limit": 100}, timeout=TIMEOUT).json()["jobs"]
    assert sorted(j["id"] for j in listed) == sorted(ids)  # none lost, none duplicated
    failed = [(j["id"], j.get("error")) for j in jobs if j["state"] != "succeeded"]
    assert not failed, f"{len(failed)} of 24 jobs failed ({runs}): {failed[:3]}"
    for j in jobs:
        assert [o["state"] for o in j["outputs"]] == ["succeeded"] * 6
    cut = sum(j["attempts"] for j in jobs) - 24
    assert cut >= 10, f"only {cut} kills cut a job short ({runs})"


def test_graceful_stop_requeues_without_counting_the_run(own_server, tmp_path):
    data = tmp_path / "data"
    s1 = own_server(args=SLOW_ARGS, data_dir=data)
    job = accepted(submit(s1.url, [("s.step", SCREW.read_bytes())], SLOW_SPEC))
    wait_for(s1.url, job["id"], lambda j: j["outputs"][1]["state"] == "running", what="rendering")
    t0 = time.monotonic()
    s1.proc.send_signal(signal.SIGTERM)
    assert s1.proc.wait(timeout=20) == 0
    assert time.monotonic() - t0 < 5  # the render was canceled, not waited for
    s2 = own_server(args=SLOW_ARGS, data_dir=data)
    job = wait_finished(s2.url, job["id"])
    assert job["state"] == "succeeded" and job["attempts"] == 1
    assert png_size(download(s2.url, job["outputs"][1])) == (SLOW_RENDER["width"], SLOW_RENDER["height"])


def test_corrupt_job_database_stops_the_start_with_a_clear_error(tmp_path):
    data = tmp_path / "data"
    data.mkdir()
    (data / "jobs.db").write_bytes(b"this is no database" * 500)
    r = subprocess.run([os.environ["NURBSRT_BIN"], "serve", "--port", "0", "--data-dir", str(data)],
                       capture_output=True, timeout=30)
    assert r.returncode != 0
    assert b"jobs.db" in r.stderr and b"not a database" in r.stderr, r.stderr[-500:]
