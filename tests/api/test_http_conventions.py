"""HTTP conventions: 405 with Allow and OPTIONS on every known resource (answered
before any body is read), 413 only for bodies and 422 for images over the size
limits, 400s that name the offending option or say what to send, conversion
downloads named after the upload, CORS for configured origins (preflight without
an API key), strong ETags with conditional GETs on job artifacts, and
Retry-After while a job is not finished."""
import hashlib
import json
import os
import socket
import subprocess
import time
import urllib.parse

import pytest
import requests

from conftest import SLOW_RENDER, BEARING, SCREW, TIMEOUT, check_problem, post_raw, validate

JOB_ID = "0123456789abcdef0123456789abcdef"
ORIGIN = "https://app.example.com"
OTHER_ORIGIN = "https://evil.example.net"
KEY = "test-key-cors-cccccccccccccccc-0003"


def raw_request(url, head, timeout=10):
    """Sends `head` (request line and headers, CRLF-terminated) on a fresh connection;
    returns (status, headers dict with lower-case names, body) of the answer."""
    parts = urllib.parse.urlsplit(url)
    with socket.create_connection((parts.hostname, parts.port), timeout=timeout) as sock:
        sock.sendall(head.encode())
        data = b""
        while b"\r\n\r\n" not in data:
            chunk = sock.recv(65536)
            if not chunk:
                break
            data += chunk
        head_bytes, _, body = data.partition(b"\r\n\r\n")
        lines = head_bytes.decode("latin-1").split("\r\n")
        headers = {k.strip().lower(): v.strip() for k, v in (line.split(":", 1) for line in lines[1:])}
        while len(body) < int(headers.get("content-length", "0")):
            chunk = sock.recv(65536)
            if not chunk:
                break
            body += chunk
    return int(lines[0].split()[1]), headers, body


# ---- 405, OPTIONS, 404 ---------------------------------------------------------------------------------

ALLOW = {
    "/v1/renders": "POST, OPTIONS",
    "/v1/conversions": "POST, OPTIONS",
    "/v1/jobs": "GET, HEAD, POST, OPTIONS",
    f"/v1/jobs/{JOB_ID}": "GET, HEAD, DELETE, OPTIONS",
    f"/v1/jobs/{JOB_ID}/artifacts/0-render-0.png": "GET, HEAD, OPTIONS",
    "/v1/files": "GET, HEAD, POST, OPTIONS",
    f"/v1/files/{'0' * 64}": "GET, HEAD, PATCH, DELETE, OPTIONS",
    f"/v1/files/{'0' * 64}/content": "GET, HEAD, OPTIONS",
    "/healthz": "GET, HEAD, OPTIONS",
    "/readyz": "GET, HEAD, OPTIONS",
    "/metrics": "GET, HEAD, OPTIONS",
    "/v1/openapi.json": "GET, HEAD, OPTIONS",
    "/": "GET, HEAD, OPTIONS",
    "/web/app.js": "GET, HEAD, OPTIONS",
}


@pytest.mark.parametrize("path", sorted(ALLOW))
def test_wrong_methods_get_405_with_allow(url, path):
    allowed = ALLOW[path].split(", ")
    for method in ("GET", "POST", "PUT", "PATCH", "DELETE"):
        if method in allowed:
            continue
        r = requests.request(method, url + path, timeout=TIMEOUT)
        body = check_problem(r, 405, "method_not_allowed")
        assert r.headers["Allow"] == ALLOW[path], (method, path)
        assert method in body["detail"] and "allowed: " + ALLOW[path] in body["detail"], body
        assert body["title"] == "Method not allowed"


def test_put_without_a_length_is_answered_at_once(url):
    """cpp-httplib reads a PUT without Content-Length until the client closes: the
    405 (and the 404 of an unknown path) must come before, not after the body timeout."""
    for path, status in (("/v1/renders", 405), ("/v1/nothing", 404), ("/healthz", 405)):
        t0 = time.monotonic()
        code, headers, body = raw_request(url, f"PUT {path} HTTP/1.1\r\nHost: x\r\n\r\n")
        assert code == status, (path, code, body[:200])
        assert time.monotonic() - t0 < 3, path
        assert json.loads(body)["status"] == status


@pytest.mark.parametrize("path", sorted(ALLOW))
def test_options_lists_the_methods(url, path):
    r = requests.options(url + path, timeout=TIMEOUT)
    assert r.status_code == 204, r.text[:200]
    assert r.headers["Allow"] == ALLOW[path]
    assert r.content == b""


def test_options_on_unknown_path_is_404(url):
    check_problem(requests.options(url + "/v1/nothing", timeout=TIMEOUT), 404, "not_found")


def test_head_where_get_is(url):
    r = requests.head(url + "/healthz", timeout=TIMEOUT)
    assert r.status_code == 200 and r.content == b""


# ---- status and messages of bad requests ------------------------------------------------------------------

def test_image_over_the_limits_is_422_naming_the_option(url):
    # tests/api.sh: --max-dimension 4096 --max-pixels 4000000
    r = post_raw(url, "/v1/renders", SCREW.read_bytes(), params={"width": 100000, "height": 10})
    detail = check_problem(r, 422, "limit_exceeded")["detail"]
    assert "'width' is 100000" in detail and "4096" in detail, detail
    r = post_raw(url, "/v1/renders", SCREW.read_bytes(), params={"width": 10, "height": 5000})
    assert "'height' is 5000" in check_problem(r, 422, "limit_exceeded")["detail"]
    r = post_raw(url, "/v1/renders", SCREW.read_bytes(), params={"width": 4000, "height": 4000})
    detail = check_problem(r, 422, "limit_exceeded")["detail"]
    assert "'width' x 'height'" in detail and "16000000" in detail and "4000000" in detail, detail


def test_oversized_body_is_still_413(url):
    r = post_raw(url, "/v1/renders", b"ISO-10303-21;\n" + b"x" * (5 << 20))
    assert check_problem(r, 413, "limit_exceeded")["title"] == "Content too large"


@pytest.mark.parametrize("path,params,options,expected", [
    ("/v1/renders", {"colour": "red"}, None, "unknown option 'colour' (render options: width, height"),
    ("/v1/renders", {}, {"camera": {"colour": 1}}, "unknown option 'colour' in 'camera' (camera options: view"),
    ("/v1/renders", {}, {"width": 64, "backgrund": "1,1,1"}, "unknown option 'backgrund'"),
    ("/v1/conversions", {"format": "stl", "colour": "red"}, None,
     "unknown option 'colour' (a conversion takes format, units, step_schema, iges_mode, deflection, angular_deflection, strict)"),
])
def test_unknown_options_are_named(url, path, params, options, expected):
    files = {"file": ("s.step", SCREW.read_bytes())}
    if options is not None:
        files["options"] = (None, json.dumps(options), "application/json")
    r = requests.post(url + path, params=params, files=files, timeout=TIMEOUT)
    detail = check_problem(r, 400, "invalid_argument")["detail"]
    assert detail.startswith(expected), detail


def test_empty_bodies_say_what_to_send(url):
    for path in ("/v1/renders", "/v1/conversions"):
        params = {"format": "stl"} if path == "/v1/conversions" else None
        detail = check_problem(post_raw(url, path, b"", params=params), 400, "invalid_argument")["detail"]
        assert detail.startswith("the request body is empty: send a STEP or IGES file"), detail
        r = requests.post(url + path, params=params, files={"file": ("a.step", b"")}, timeout=TIMEOUT)
        detail = check_problem(r, 400, "invalid_argument")["detail"]
        assert detail.startswith("the 'file' part is empty: send a STEP or IGES file"), detail


@pytest.mark.parametrize("path,expected", [
    ("/v1/renders", "send a STEP or IGES file"),
    ("/v1/conversions", "send a STEP or IGES file"),
    ("/v1/jobs", "a job is multipart/form-data"),
])
def test_post_without_any_body_is_400_at_once(url, path, expected):
    t0 = time.monotonic()
    status, headers, body = raw_request(url, f"POST {path} HTTP/1.1\r\nHost: x\r\n\r\n")
    assert time.monotonic() - t0 < 3
    assert status == 400, body[:300]
    problem = json.loads(body)
    validate(problem, "Problem")
    assert problem["detail"].startswith("the request has no body"), problem
    assert expected in problem["detail"]


# ---- proactive negotiation (RFC 9110 §12.5.1): Accept decides the answer, 406 when it admits none ----------

IMAGE_MAGIC = {"image/png": b"\x89PNG", "image/jpeg": b"\xff\xd8\xff", "image/tiff": b"II*\x00",
               "image/x-exr": b"\x76\x2f\x31\x01"}


@pytest.mark.parametrize("accept,content_type", [
    (None, "image/png"), ("*/*", "image/png"), ("image/jpeg", "image/jpeg"), ("image/tiff", "image/tiff"),
    ("image/x-exr", "image/x-exr"), ("image/png;q=0.5, image/jpeg", "image/jpeg"), ("image/*", "image/png"),
    ("application/json, */*", "application/json"),
])
def test_render_answers_what_accept_prefers(url, accept, content_type):
    r = post_raw(url, "/v1/renders", SCREW.read_bytes(), params={"width": 48, "height": 32},
                 headers={"Accept": accept} if accept else {})
    assert r.status_code == 200, r.text[:300]
    assert r.headers["Content-Type"].startswith(content_type)
    if content_type == "application/json":
        assert r.json()["format"] == "png"
    else:
        assert r.content.startswith(IMAGE_MAGIC[content_type])


def test_render_refuses_what_accept_does_not_admit(url):
    for accept in ("application/xml", "text/html", "image/gif", "image/png;q=0, application/json;q=0"):
        r = post_raw(url, "/v1/renders", SCREW.read_bytes(), params={"width": 48}, headers={"Accept": accept})
        check_problem(r, 406, "not_acceptable")
        for offered in ("image/png", "image/jpeg", "image/tiff", "image/x-exr", "application/json"):
            assert offered in r.json()["detail"], (accept, r.json()["detail"])
    # A format the options name is the only image on offer: Accept must admit it (or JSON).
    r = post_raw(url, "/v1/renders", SCREW.read_bytes(), params={"width": 48, "format": "png"},
                 headers={"Accept": "image/jpeg"})
    check_problem(r, 406, "not_acceptable")
    assert "image/png" in r.json()["detail"] and "image/jpeg" not in r.json()["detail"]
    r = post_raw(url, "/v1/renders", SCREW.read_bytes(), params={"width": 48, "format": "jpeg"},
                 headers={"Accept": "image/*"})
    assert r.status_code == 200 and r.headers["Content-Type"] == "image/jpeg"


def test_conversion_refuses_what_accept_does_not_admit(url):
    r = requests.post(url + "/v1/conversions", files={"file": ("screw.step", SCREW.read_bytes()), "format": (None, "stl")},
                      headers={"Accept": "application/xml"}, timeout=TIMEOUT)
    check_problem(r, 406, "not_acceptable")
    assert "model/stl" in r.json()["detail"] and "application/json" in r.json()["detail"]
    r = requests.post(url + "/v1/conversions", files={"file": ("screw.step", SCREW.read_bytes()), "format": (None, "stl")},
                      headers={"Accept": "model/*"}, timeout=TIMEOUT)
    assert r.status_code == 200 and r.headers["Content-Type"] == "model/stl"


# ---- conversions: format as a form field, download names ----------------------------------------------

@pytest.mark.parametrize("upload_name,fmt,download,magic", [
    ("bearing.step", "step", "bearing.stp", b"ISO-10303-21;"),
    ("bearing.step", "iges", "bearing.igs", None),
    ("C:\\parts\\my part.v2.STEP", "stl", "mypart.v2.stl", None),
])
def test_conversion_format_as_form_field_and_download_name(url, upload_name, fmt, download, magic):
    r = requests.post(url + "/v1/conversions", files={"file": (upload_name, SCREW.read_bytes()), "format": (None, fmt)},
                      timeout=TIMEOUT)
    assert r.status_code == 200, r.text[:300]
    assert r.headers["Content-Disposition"] == f"attachment; filename=\"{download}\"; filename*=UTF-8''{download}"
    if magic:
        assert r.content.startswith(magic)
    if fmt == "iges":
        assert r.content[72:73] == b"S"  # IGES: the Start section's letter in column 73


# ---- CORS -----------------------------------------------------------------------------------------------

@pytest.fixture
def cors_server(own_server, tmp_path):
    keys = tmp_path / "keys"
    keys.write_text(KEY + "\n")
    return own_server(args=["--cors-origin", ORIGIN, "--cors-origin", "http://localhost:3000",
                            "--api-keys-file", str(keys)])


def preflight(base, path, origin, method="POST"):
    return requests.options(base + path, timeout=TIMEOUT, headers={
        "Origin": origin, "Access-Control-Request-Method": method,
        "Access-Control-Request-Headers": "authorization, x-api-key, content-type"})


def test_cors_preflight_needs_no_key(cors_server):
    for path in ("/v1/renders", "/v1/jobs", f"/v1/jobs/{JOB_ID}"):
        r = preflight(cors_server.url, path, ORIGIN)
        assert r.status_code == 204, (path, r.text[:300])
        assert r.content == b""
        assert r.headers["Access-Control-Allow-Origin"] == ORIGIN
        assert r.headers["Access-Control-Allow-Methods"] == ALLOW[path]
        allowed = [h.strip().lower() for h in r.headers["Access-Control-Allow-Headers"].split(",")]
        assert {"authorization", "x-api-key", "content-type"} <= set(allowed), allowed
        assert int(r.headers["Access-Control-Max-Age"]) > 0
        assert "Origin" in r.headers["Vary"]
    # The second configured origin too, compared without regard to case.
    r = preflight(cors_server.url, "/v1/renders", "http://LOCALHOST:3000")
    assert r.headers["Access-Control-Allow-Origin"] == "http://LOCALHOST:3000"


def test_cors_disallowed_origin_gets_no_cors_headers(cors_server):
    for origin in (OTHER_ORIGIN, ORIGIN + ".evil.net", "https://app.example.com:444", "null"):
        r = preflight(cors_server.url, "/v1/renders", origin)
        assert r.status_code == 204
        assert not [h for h in r.headers if h.lower().startswith("access-control-")], (origin, r.headers)
        r = requests.get(cors_server.url + "/healthz", headers={"Origin": origin}, timeout=TIMEOUT)
        assert r.status_code == 200
        assert "Access-Control-Allow-Origin" not in r.headers
        assert "Origin" in r.headers["Vary"]


def test_cors_simple_and_refused_answers_carry_the_origin(cors_server):
    r = requests.get(cors_server.url + "/healthz", headers={"Origin": ORIGIN}, timeout=TIMEOUT)
    assert r.status_code == 200 and r.headers["Access-Control-Allow-Origin"] == ORIGIN
    assert "X-Request-Id" in r.headers["Access-Control-Expose-Headers"]
    # A refusal is readable by the page: 401 without a key, 405, a render's 400.
    r = requests.get(cors_server.url + "/v1/jobs", headers={"Origin": ORIGIN}, timeout=TIMEOUT)
    check_problem(r, 401, "unauthorized")
    assert r.headers["Access-Control-Allow-Origin"] == ORIGIN
    auth = {"Origin": ORIGIN, "Authorization": f"Bearer {KEY}"}
    r = requests.get(cors_server.url + "/v1/renders", headers=auth, timeout=TIMEOUT)
    check_problem(r, 405)
    assert r.headers["Access-Control-Allow-Origin"] == ORIGIN
    r = post_raw(cors_server.url, "/v1/renders", SCREW.read_bytes(), params={"colour": "red"}, headers=auth)
    check_problem(r, 400, "invalid_argument")
    assert r.headers["Access-Control-Allow-Origin"] == ORIGIN
    # No Origin: no CORS answer, but Vary still says the answer depends on it.
    r = requests.get(cors_server.url + "/healthz", timeout=TIMEOUT)
    assert "Access-Control-Allow-Origin" not in r.headers and "Origin" in r.headers["Vary"]


def test_api_key_in_x_api_key(cors_server):
    """The key a preflight allows as X-Api-Key is accepted as well as Authorization: Bearer."""
    base = cors_server.url
    r = requests.get(base + "/v1/jobs", headers={"Origin": ORIGIN, "X-Api-Key": KEY}, timeout=TIMEOUT)
    assert r.status_code == 200, r.text[:300]
    assert r.headers["Access-Control-Allow-Origin"] == ORIGIN
    validate(r.json(), "JobList")
    r = requests.get(base + "/v1/jobs", headers={"X-Api-Key": KEY + "x"}, timeout=TIMEOUT)
    assert check_problem(r, 401, "unauthorized")["detail"] == "the API key is not valid"
    r = requests.get(base + "/v1/jobs", headers={"X-Api-Key": ""}, timeout=TIMEOUT)
    check_problem(r, 401, "unauthorized")
    r = requests.get(base + "/v1/jobs", timeout=TIMEOUT)
    assert "'X-Api-Key: <key>'" in check_problem(r, 401, "unauthorized")["detail"]
    r = post_raw(base, "/v1/renders", SCREW.read_bytes(), params={"width": 32, "height": 24},
                 headers={"X-Api-Key": KEY})
    assert r.status_code == 200 and r.content.startswith(b"\x89PNG")


def test_cors_is_off_by_default(url):
    r = preflight(url, "/v1/renders", ORIGIN)
    assert r.status_code == 204 and r.headers["Allow"] == "POST, OPTIONS"
    assert not [h for h in r.headers if h.lower().startswith("access-control-")]
    r = requests.get(url + "/healthz", headers={"Origin": ORIGIN}, timeout=TIMEOUT)
    assert "Access-Control-Allow-Origin" not in r.headers and "Origin" not in r.headers.get("Vary", "")


def test_cors_origins_from_the_environment(own_server):
    s = own_server(env={"NURBSRT_CORS_ORIGIN": f"{ORIGIN},http://127.0.0.1:8000"})
    for origin in (ORIGIN, "http://127.0.0.1:8000"):
        r = requests.get(s.url + "/healthz", headers={"Origin": origin}, timeout=TIMEOUT)
        assert r.headers["Access-Control-Allow-Origin"] == origin


@pytest.mark.parametrize("origin", ["https://app.example.com/", "*", "app.example.com", "ftp://x.org",
                                    "https://app.example.com/path"])
def test_cors_origin_that_is_no_origin_stops_the_start(tmp_path, origin):
    try:
        p = subprocess.run([os.environ["NURBSRT_BIN"], "serve", "--port", "0", "--data-dir", str(tmp_path / "d"),
                            "--cors-origin", origin], capture_output=True, text=True, timeout=30)
    except subprocess.TimeoutExpired:
        pytest.fail(f"the service started with --cors-origin {origin!r}")
    assert p.returncode != 0
    assert "is not an origin" in p.stderr, p.stderr[-500:]


# ---- jobs: ETag, Cache-Control, 304, Retry-After -------------------------------------------------------

def submit(base, spec, data=None):
    parts = [("file", ("s.step", data or SCREW.read_bytes(), "application/octet-stream")),
             ("job", (None, json.dumps(spec), "application/json"))]
    return requests.post(base + "/v1/jobs", files=parts, timeout=TIMEOUT)


def wait_finished(base, job_id, timeout=120):
    deadline = time.monotonic() + timeout
    while True:
        r = requests.get(f"{base}/v1/jobs/{job_id}", timeout=TIMEOUT)
        job = r.json()
        if job["state"] in ("succeeded", "failed", "canceled"):
            return r
        assert int(r.headers["Retry-After"]) >= 1, "a job that is not finished says when to poll again"
        assert time.monotonic() < deadline
        time.sleep(0.2)


def test_artifacts_have_a_strong_etag_and_answer_304(url):
    r = submit(url, {"outputs": [{"file": 0, "type": "render", "options": {"width": 64, "height": 48}},
                                 {"file": 0, "type": "conversion", "format": "stl"}]})
    assert r.status_code == 202, r.text[:300]
    assert int(r.headers["Retry-After"]) >= 1
    done = wait_finished(url, r.json()["id"])
    assert done.json()["state"] == "succeeded", done.text[:500]
    assert "Retry-After" not in done.headers, "a finished job needs no more polling"
    for out in done.json()["outputs"]:
        art_url = url + out["artifact"]["url"]
        r = requests.get(art_url, timeout=TIMEOUT)
        assert r.status_code == 200
        etag = r.headers["ETag"]
        assert etag == '"' + hashlib.sha256(r.content).hexdigest() + '"', "strong, from the content"
        cache = [d.strip() for d in r.headers["Cache-Control"].split(",")]
        assert "private" in cache and "immutable" in cache, cache
        assert int(next(d for d in cache if d.startswith("max-age="))[8:]) > 0
        assert requests.get(art_url, timeout=TIMEOUT).headers["ETag"] == etag, "stable"
        for header in (etag, "W/" + etag, f'"nope", {etag}', "*"):
            r304 = requests.get(art_url, headers={"If-None-Match": header}, timeout=TIMEOUT)
            assert r304.status_code == 304, header
            assert r304.content == b""
            assert r304.headers["ETag"] == etag and "immutable" in r304.headers["Cache-Control"]
        other = requests.get(art_url, headers={"If-None-Match": '"0000"'}, timeout=TIMEOUT)
        assert other.status_code == 200 and other.content == r.content


def test_retry_after_while_queued_or_running(own_server):
    s = own_server(args=["--job-runners", "1", "--render-threads", "1"])
    slow = {"outputs": [{"file": 0, "type": "render", "options": SLOW_RENDER}]}
    first = submit(s.url, slow, BEARING.read_bytes())
    second = submit(s.url, slow, BEARING.read_bytes())
    for r in (first, second):
        assert r.status_code == 202 and int(r.headers["Retry-After"]) >= 1
    # With one runner the second job waits behind the first: queued, then running.
    r = requests.get(f"{s.url}/v1/jobs/{second.json()['id']}", timeout=TIMEOUT)
    assert r.json()["state"] in ("queued", "running")
    assert int(r.headers["Retry-After"]) >= 1
    for job in (first, second):
        d = requests.delete(f"{s.url}/v1/jobs/{job.json()['id']}", timeout=TIMEOUT)
        assert d.status_code in (202, 204)
        if d.status_code == 202:
            assert int(d.headers["Retry-After"]) >= 1
