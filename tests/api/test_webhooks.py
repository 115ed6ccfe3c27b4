"""Webhooks: a job naming a callback_url has its final document POSTed to a
receiver on loopback, signed with HMAC-SHA256 over the body (checked here with
Python's hmac), retried with doubling back-off after failures until delivered
or given up; the job shows the delivery; callback URLs that are malformed,
point at private addresses, or reach a service without a secret are refused
before 202; a name resolving to a private address fails at delivery."""
import hashlib
import hmac
import http.server
import json
import socket
import threading
import time

import pytest
import requests

from conftest import SCREW, TIMEOUT, check_problem, validate
from test_jobs import accepted, get_job, submit, wait_for

SECRET = "test-webhook-secret-0123456789"
BACKOFF_S = 0.3
ATTEMPTS = 3


class Receiver:
    """An HTTP server on a free loopback port answering POSTs with the next status of `statuses`
    (the last one repeats); it records (arrival time, path, headers, body) of each."""

    def __init__(self, statuses):
        self.statuses = list(statuses)
        self.calls = []
        outer = self

        class Handler(http.server.BaseHTTPRequestHandler):
            def do_POST(self):
                body = self.rfile.read(int(self.headers.get("Content-Length", 0)))
                outer.calls.append((time.monotonic(), self.path, dict(self.headers), body))
                status = outer.statuses[min(len(outer.calls), len(outer.statuses)) - 1]
                self.send_response(status)
                self.send_header("Content-Length", "0")
                self.end_headers()

            def log_message(self, *args):
                pass

        self.httpd = http.server.ThreadingHTTPServer(("127.0.0.1", 0), Handler)
        self.url = f"http://127.0.0.1:{self.httpd.server_address[1]}"
        self.thread = threading.Thread(target=self.httpd.serve_forever, daemon=True)
        self.thread.start()

    def close(self):
        self.httpd.shutdown()
        self.httpd.server_close()


@pytest.fixture
def receiver():
    made = []

    def make(statuses):
        r = Receiver(statuses)
        made.append(r)
        return r

    yield make
    for r in made:
        r.close()


def hook_server(own_server, allow_private=True):
    args = ["--webhook-backoff", str(BACKOFF_S), "--webhook-attempts", str(ATTEMPTS), "--webhook-timeout", "5"]
    return own_server(args + (["--webhook-allow-private"] if allow_private else []),
                      env={"NURBSRT_WEBHOOK_SECRET": SECRET})


def job_spec(callback_url):
    return {"outputs": [{"file": 0, "type": "render", "options": {"width": 64, "height": 48}},
                        {"file": 0, "type": "conversion", "format": "stl"}],
            "callback_url": callback_url}


def submit_with_callback(base, callback_url):
    job = accepted(submit(base, [("screw.step", SCREW.read_bytes())], job_spec(callback_url)))
    assert job["callback"]["url"] == callback_url
    assert job["callback"]["state"] == "waiting" and job["callback"]["attempts"] == 0
    return job


def callback_done(base, job_id, timeout=60):
    return wait_for(base, job_id, lambda j: j["callback"]["state"] in ("delivered", "failed"), timeout,
                    "a delivered or failed callback")


def signature_ok(headers, body):
    expected = "sha256=" + hmac.new(SECRET.encode(), body, hashlib.sha256).hexdigest()
    return hmac.compare_digest(headers.get("X-Nurbsrt-Signature", ""), expected)


def test_callback_is_signed_and_retried_until_delivered(own_server, receiver):
    s = hook_server(own_server)
    rx = receiver([503, 500, 204])
    job = submit_with_callback(s.url, rx.url + "/hooks/nurbsrt?team=7")
    done = callback_done(s.url, job["id"])
    assert done["state"] == "succeeded"
    cb = done["callback"]
    assert cb["state"] == "delivered", cb
    assert cb["attempts"] == 3 and cb["last_status"] == 204 and cb["last_error"] is None
    assert cb["next_attempt_at"] is None and cb["finished_at"] is not None
    assert len(rx.calls) == 3
    bodies = set()
    for n, (_, path, headers, body) in enumerate(rx.calls, start=1):
        assert path == "/hooks/nurbsrt?team=7"
        assert headers["Content-Type"] == "application/json"
        assert headers["X-Nurbsrt-Event"] == "job.finished"
        assert headers["X-Nurbsrt-Delivery"] == job["id"]
        assert headers["X-Nurbsrt-Attempt"] == str(n)
        assert signature_ok(headers, body), headers.get("X-Nurbsrt-Signature")
        assert not signature_ok(headers, body + b" ")  # the signature covers the exact bytes
        bodies.add(body)
    assert len(bodies) == 1, "every attempt sends the same bytes"
    sent = json.loads(bodies.pop())
    validate(sent, "Job")
    assert "callback" not in sent
    assert sent["id"] == job["id"] and sent["state"] == "succeeded"
    assert [o["state"] for o in sent["outputs"]] == ["succeeded", "succeeded"]
    assert all(o["artifact"]["url"].startswith(f"/v1/jobs/{job['id']}/artifacts/") for o in sent["outputs"])
    # Back-off: at least the base delay, then at least twice it.
    times = [c[0] for c in rx.calls]
    assert times[1] - times[0] >= BACKOFF_S * 0.95, times
    assert times[2] - times[1] >= 2 * BACKOFF_S * 0.95, times
    metrics = requests.get(s.url + "/metrics", timeout=TIMEOUT).text
    assert 'nurbsrt_webhook_attempts_total{outcome="delivered"} 1' in metrics
    assert 'nurbsrt_webhook_attempts_total{outcome="retry"} 2' in metrics


def test_callback_is_given_up_after_the_attempts(own_server, receiver):
    s = hook_server(own_server)
    rx = receiver([500])
    job = submit_with_callback(s.url, rx.url + "/down")
    cb = callback_done(s.url, job["id"])["callback"]
    assert cb["state"] == "failed", cb
    assert cb["attempts"] == ATTEMPTS and cb["last_status"] == 500
    assert cb["last_error"] == "answered HTTP 500"
    time.sleep(3 * BACKOFF_S)
    assert len(rx.calls) == ATTEMPTS, "no attempt after giving up"
    # A receiver that is not listening at all: no status, the connection error instead.
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        closed_port = probe.getsockname()[1]
    job = submit_with_callback(s.url, f"http://127.0.0.1:{closed_port}/gone")
    cb = callback_done(s.url, job["id"])["callback"]
    assert cb["state"] == "failed" and cb["attempts"] == ATTEMPTS and cb["last_status"] is None, cb
    assert cb["last_error"].startswith("no answer"), cb


def test_callback_urls_are_checked_before_202(url, own_server):
    screw = [("screw.step", SCREW.read_bytes())]
    # The shared server has no secret: a callback would go out unsigned, so none is accepted.
    body = check_problem(submit(url, screw, job_spec("https://hooks.example.com/x")), 400, "invalid_argument")
    assert "callback_url" in body["detail"] and "secret" in body["detail"], body
    s = hook_server(own_server, allow_private=False)
    cases = {
        "ftp://hooks.example.com/x": "http:// or https://",
        "https://user:pw@hooks.example.com/x": "user information",
        "https://hooks.example.com/x#y": "fragment",
        "https://hooks.example.com:70000/x": "port",
        "http://127.0.0.1:9/x": "loopback, private or link-local",
        "http://169.254.169.254/latest/meta-data": "loopback, private or link-local",
        "http://[::1]/x": "loopback, private or link-local",
        "http://localhost:9/x": "loopback, private or link-local",
        # Every spelling of loopback the resolver takes as an address (inet_aton's), refused at submission:
        **{f"http://{host}:9/x": "loopback, private or link-local"
           for host in ("0x7f000001", "2130706433", "0177.0.0.1", "127.1", "0", "127.000.000.001")},
    }
    for callback, reason in cases.items():
        body = check_problem(submit(s.url, screw, job_spec(callback)), 400, "invalid_argument")
        assert body["detail"].startswith("callback_url ") and reason in body["detail"], (callback, body)
    body = check_problem(submit(s.url, screw, {**job_spec(""), "callback_url": 7}), 400, "invalid_argument")
    assert "callback_url" in body["detail"]
    assert requests.get(s.url + "/v1/jobs", timeout=TIMEOUT).json()["jobs"] == [], "nothing was queued"


def test_a_name_resolving_to_a_private_address_fails_at_delivery(own_server):
    name = socket.gethostname()
    try:
        addresses = {a[4][0] for a in socket.getaddrinfo(name, 80, type=socket.SOCK_STREAM)}
    except OSError:
        pytest.skip(f"the host name {name} does not resolve here")
    private = lambda a: a.startswith(("127.", "10.", "192.168.", "169.254.")) or a == "::1" or \
        (a.startswith("172.") and 16 <= int(a.split(".")[1]) <= 31)
    if not all(private(a) for a in addresses):
        pytest.skip(f"the host name {name} resolves to {addresses}, not only to private addresses")
    s = hook_server(own_server, allow_private=False)
    job = submit_with_callback(s.url, f"http://{name}:9/x")
    cb = callback_done(s.url, job["id"])["callback"]
    assert cb["state"] == "failed" and cb["attempts"] == 1, cb  # no retry can make it public
    assert "resolves to the non-public address" in cb["last_error"], cb
