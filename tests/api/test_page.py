"""The web page (GET / and /web/{name}: compiled into the binary, strict
Content-Security-Policy, open without an API key) and the `aovs` option of
POST /v1/renders that the page reads its AOV views from."""
import base64
import json
import math
import re
import struct

import requests

from conftest import SCREW, TIMEOUT, check_problem, post_raw, validate

KEY = "test-key-page-aaaaaaaaaaaa-0001"


def test_page_and_its_modules(url):
    r = requests.get(url + "/", timeout=TIMEOUT)
    assert r.status_code == 200
    assert r.headers["Content-Type"].startswith("text/html")
    csp = r.headers["Content-Security-Policy"]
    assert "default-src 'self'" in csp and "script-src 'self'" in csp and "style-src 'self'" in csp
    assert "unsafe-inline" not in csp and "unsafe-eval" not in csp
    assert r.headers["X-Content-Type-Options"] == "nosniff"
    assert "frame-ancestors 'none'" in csp
    # No inline script or style (the CSP would block them) and nothing from elsewhere.
    assert not re.search(r"<script(?![^>]*\bsrc=)", r.text)
    assert "<style" not in r.text and " style=" not in r.text
    assert not re.search(r"(src|href)=\"(https?:)?//", r.text)
    modules = set(re.findall(r"(?:src|href)=\"/web/([^\"]+)\"", r.text))
    assert "app.js" in modules and "style.css" in modules
    seen = set()
    while modules:
        name = modules.pop()
        seen.add(name)
        m = requests.get(url + "/web/" + name, timeout=TIMEOUT)
        assert m.status_code == 200, name
        want = "text/css" if name.endswith(".css") else "text/javascript"
        assert m.headers["Content-Type"].startswith(want), (name, m.headers["Content-Type"])
        assert m.headers["X-Content-Type-Options"] == "nosniff"
        assert "http://" not in m.text and "https://" not in m.text, f"{name} refers to another origin"
        # Follow the module graph: every import resolves to an embedded file.
        for dep in re.findall(r"from '\./([^']+)'", m.text):
            if dep not in seen:
                modules.add(dep)
    assert {"api.js", "scheduler.js", "aov.js"} <= seen


def test_missing_page_file_is_a_problem(url):
    check_problem(requests.get(url + "/web/nothing.js", timeout=TIMEOUT), 404, "not_found")
    check_problem(requests.get(url + "/web/..%2Fserver.cpp", timeout=TIMEOUT), 404)


def test_page_is_open_but_the_api_is_not_with_keys(own_server):
    s = own_server(env={"NURBSRT_API_KEYS": KEY})
    assert requests.get(s.url + "/", timeout=TIMEOUT).status_code == 200
    assert requests.get(s.url + "/web/app.js", timeout=TIMEOUT).status_code == 200
    check_problem(post_raw(s.url, "/v1/renders", SCREW.read_bytes(), {"width": 32}), 401, "unauthorized")


def aov_array(aov, width, height):
    fmt = {"float32": "f", "uint32": "I", "uint8": "B"}[aov["type"]]
    raw = base64.b64decode(aov["data"])
    n = width * height * aov["components"]
    assert len(raw) == n * struct.calcsize(fmt)
    return struct.unpack("<" + fmt * n, raw)


def test_render_returns_aovs_as_raw_arrays(url):
    w, h = 96, 72
    opts = {"width": w, "height": h, "view": "iso", "aovs": ["z", "face", "normal", "uv", "iterations"]}
    r = requests.post(url + "/v1/renders", headers={"Accept": "application/json"}, timeout=TIMEOUT,
                      files={"file": ("screw.step", SCREW.read_bytes()), "options": (None, json.dumps(opts))})
    assert r.status_code == 200, r.text[:300]
    body = r.json()
    validate(body, "RenderResponse")
    aovs = body["aovs"]
    assert set(aovs) == {"z", "face", "normal", "uv", "iterations"}
    face = aov_array(aovs["face"], w, h)
    z = aov_array(aovs["z"], w, h)
    normal = aov_array(aovs["normal"], w, h)
    iterations = aov_array(aovs["iterations"], w, h)
    aov_array(aovs["uv"], w, h)
    hit = [i for i in range(w * h) if face[i]]
    assert len(hit) == body["statistics"]["pixels_hit"] > 0
    assert max(face) <= body["statistics"]["faces"]
    assert all(math.isfinite(z[i]) and z[i] > 0 for i in hit)
    assert all(math.isinf(z[i]) for i in range(w * h) if not face[i])
    for i in hit[:: max(1, len(hit) // 50)]:
        assert abs(math.hypot(*normal[3 * i:3 * i + 3]) - 1) < 1e-3
    assert any(iterations[i] > 0 for i in hit)


def test_aovs_as_query_parameter_and_refusals(url):
    data = SCREW.read_bytes()
    r = post_raw(url, "/v1/renders", data, {"width": 40, "aovs": "face,z"}, {"Accept": "application/json"})
    assert r.status_code == 200, r.text[:300]
    assert set(r.json()["aovs"]) == {"face", "z"}
    # The image answer has no room for AOVs: refused, not silently dropped.
    body = check_problem(post_raw(url, "/v1/renders", data, {"width": 40, "aovs": "face"}), 400, "invalid_argument")
    assert "Accept" in body["detail"]
    body = check_problem(post_raw(url, "/v1/renders", data, {"width": 40, "aovs": "face,colour"},
                                  {"Accept": "application/json"}), 400, "invalid_argument")
    assert "colour" in body["detail"]
    job = {"outputs": [{"file": 0, "type": "render", "options": {"width": 40, "aovs": ["z"]}}]}
    r = requests.post(url + "/v1/jobs", timeout=TIMEOUT,
                      files=[("file", ("screw.step", data)), ("job", (None, json.dumps(job)))])
    assert "aovs" in check_problem(r, 400, "invalid_argument")["detail"]
