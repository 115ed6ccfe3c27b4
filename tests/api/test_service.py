"""Service endpoints: health, readiness, metrics, the OpenAPI document, 404s, request ids."""
import json
import os
import re

import requests

from conftest import REPO, TIMEOUT, check_problem, healthy, validate


def test_healthz(url):
    healthy(url)


def test_readyz(url):
    r = requests.get(url + "/readyz", timeout=TIMEOUT)
    assert r.status_code in (200, 503)
    validate(r.json(), "Readiness")
    assert r.json()["max_active"] == 2 and r.json()["max_queued"] == 2


def test_openapi_is_the_embedded_schema(url):
    r = requests.get(url + "/v1/openapi.json", timeout=TIMEOUT)
    assert r.status_code == 200
    assert r.json() == json.loads((REPO / "api_schema" / "openapi.json").read_text())
    assert r.json()["openapi"].startswith("3.1")


def test_unknown_route_is_a_problem(url):
    check_problem(requests.get(url + "/v1/nothing", timeout=TIMEOUT), 404, "not_found")


def test_request_id_is_echoed_when_safe_and_replaced_when_not(url):
    r = requests.get(url + "/healthz", headers={"X-Request-Id": "abc-123.x_y"}, timeout=TIMEOUT)
    assert r.headers["X-Request-Id"] == "abc-123.x_y"
    r = requests.get(url + "/healthz", headers={"X-Request-Id": "bad id; rm -rf /"}, timeout=TIMEOUT)
    assert r.headers["X-Request-Id"] != "bad id; rm -rf /"
    assert len(r.headers["X-Request-Id"]) == 32
    a = requests.get(url + "/healthz", timeout=TIMEOUT).headers["X-Request-Id"]
    b = requests.get(url + "/healthz", timeout=TIMEOUT).headers["X-Request-Id"]
    assert a != b


def test_metrics_exposition(url):
    requests.get(url + "/healthz", timeout=TIMEOUT)
    r = requests.get(url + "/metrics", timeout=TIMEOUT)
    assert r.status_code == 200
    assert r.headers["Content-Type"].startswith("text/plain")
    text = r.text
    assert 'nurbsrt_http_requests_total{route="/healthz",status="200"}' in text
    assert 'nurbsrt_http_request_duration_seconds_bucket{route="/healthz",le="+Inf"}' in text
    assert "nurbsrt_work_max_active 2" in text
    assert "# TYPE nurbsrt_import_failures_total counter" in text
    # Which instance answered, and its job store (several instances may sit behind one balancer).
    store = "postgresql" if os.environ.get("NURBSRT_API_JOB_STORE") else "sqlite"
    assert re.search(r'^nurbsrt_instance_info\{instance="[A-Za-z0-9._-]+",job_store="' + store + r'"\} 1$', text, re.M)
    for line in text.splitlines():  # every sample line is "name{labels} value" or "name value"
        if line and not line.startswith("#"):
            float(line.rsplit(" ", 1)[1])
