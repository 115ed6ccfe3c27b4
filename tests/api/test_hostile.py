"""Hostile and careless clients: compressed-body bombs, slow and lying requests,
connection floods and bursts. Each gets its answer at once or at the configured
deadline, without the service spending memory or threads on it, and every other
client (the health probe above all) keeps being answered promptly."""
import json
import os
import pathlib
import socket
import statistics
import subprocess
import tempfile
import threading
import time
import zlib
from urllib.parse import urlparse

import pytest
import requests

from conftest import BEARING, SCREW, SLOW_RENDER, TIMEOUT, check_problem, healthy, post_raw, validate


def address(url):
    u = urlparse(url)
    return u.hostname, u.port


def read_response(sock, timeout=15, no_body=False):
    """(status, headers dict with lower-case names, body bytes) of one HTTP/1.1 answer (to a HEAD request:
    no body follows its Content-Length)."""
    sock.settimeout(timeout)
    data = b""
    while b"\r\n\r\n" not in data:
        chunk = sock.recv(65536)
        if not chunk:
            raise ConnectionError(f"closed before an answer: {data[:200]!r}")
        data += chunk
    head, _, body = data.partition(b"\r\n\r\n")
    lines = head.decode("latin-1").split("\r\n")
    status = int(lines[0].split()[1])
    headers = {k.strip().lower(): v.strip() for k, v in (line.split(":", 1) for line in lines[1:])}
    length = 0 if no_body else int(headers.get("content-length", "0"))
    while len(body) < length:
        chunk = sock.recv(65536)
        if not chunk:
            break
        body += chunk
    return status, headers, body[:length]


def problem_of(status, headers, body, want_status, want_code):
    assert status == want_status, (status, body[:300])
    assert headers["content-type"].startswith("application/problem+json")
    p = json.loads(body)
    validate(p, "Problem")
    assert p["status"] == want_status and p["code"] == want_code, p
    assert p["request_id"] == headers["x-request-id"]
    return p


def connect(url):
    return socket.create_connection(address(url), timeout=30)


def peak_rss_mb(pid):
    for line in open(f"/proc/{pid}/status"):
        if line.startswith("VmHWM:"):
            return int(line.split()[1]) / 1024
    raise AssertionError("no VmHWM")


def gzip_of_spaces(total_mb):
    """A valid gzip stream of a STEP header and `total_mb` MiB of spaces (~1000:1)."""
    c = zlib.compressobj(9, zlib.DEFLATED, 31)
    out = [c.compress(b"ISO-10303-21;\nHEADER;\n")]
    block = b" " * (1 << 20)
    for _ in range(total_mb):
        out.append(c.compress(block))
    out.append(c.flush())
    return b"".join(out)


def test_compressed_bodies_refused_without_inflating(own_server):
    s = own_server(args=["--max-upload-mb", "4"])
    bomb = gzip_of_spaces(256)  # 256 KiB on the wire, 256 MiB inflated
    assert len(bomb) < 1 << 20
    before = peak_rss_mb(s.proc.pid)
    for encoding in ("gzip", "deflate", "br", "GZIP, identity"):
        t = time.monotonic()
        r = post_raw(s.url, "/v1/renders", bomb, {"width": 64, "height": 48}, {"Content-Encoding": encoding})
        check_problem(r, 415, "unsupported_format")
        assert "Content-Encoding" in r.json()["detail"]
        assert time.monotonic() - t < 5
    # The same through a multipart upload and a job.
    r = requests.post(s.url + "/v1/conversions", data=bomb, timeout=TIMEOUT,
                      headers={"Content-Encoding": "gzip", "Content-Type": "multipart/form-data; boundary=x"})
    check_problem(r, 415, "unsupported_format")
    # Nothing was inflated: the peak memory of the service did not grow by the bomb.
    assert peak_rss_mb(s.proc.pid) - before < 64, (before, peak_rss_mb(s.proc.pid))
    # "identity" is no encoding at all.
    r = post_raw(s.url, "/v1/renders", SCREW.read_bytes(), {"width": 64, "height": 48},
                 {"Content-Encoding": "identity"})
    assert r.status_code == 200, r.text[:300]


def test_refused_before_the_body_is_sent(own_server):
    """With Expect: 100-continue (curl, large uploads) the refusal comes instead of
    the go-ahead, so the client never sends the body; a lying Content-Length over
    the limit is answered at once instead of after waiting for its bytes."""
    s = own_server(args=["--max-upload-mb", "1"])
    cases = [
        ({"Content-Length": str(50 << 20), "Expect": "100-continue"}, 413, "limit_exceeded"),
        ({"Content-Length": "10000000000000"}, 413, "limit_exceeded"),
        ({"Content-Length": "1000", "Content-Encoding": "gzip", "Expect": "100-continue"}, 415,
         "unsupported_format"),
        ({"Content-Length": "12abc"}, 400, "malformed_request"),  # no length to frame the body by
    ]
    for extra, status, code in cases:
        with connect(s.url) as sock:
            head = "POST /v1/renders HTTP/1.1\r\nHost: x\r\nContent-Type: application/octet-stream\r\n"
            head += "".join(f"{k}: {v}\r\n" for k, v in extra.items()) + "\r\n"
            t = time.monotonic()
            sock.sendall(head.encode())
            answer = read_response(sock, timeout=5)
            assert time.monotonic() - t < 2
            problem_of(*answer, status, code)
            assert answer[1].get("connection") == "close"
    healthy(s.url)


def test_chunked_body_over_the_limit(own_server):
    s = own_server(args=["--max-upload-mb", "1"])
    with connect(s.url) as sock:
        sock.sendall(b"POST /v1/renders HTTP/1.1\r\nHost: x\r\nContent-Type: application/octet-stream\r\n"
                     b"Transfer-Encoding: chunked\r\n\r\n")
        chunk = b" " * 65536
        try:
            for _ in range(48):  # 3 MiB in 64 KiB chunks, over the 1 MiB limit
                sock.sendall(b"%x\r\n" % len(chunk) + chunk + b"\r\n")
            sock.sendall(b"0\r\n\r\n")
        except OSError:
            pass  # the service answered and stopped reading: the answer is still there
        problem_of(*read_response(sock), 413, "limit_exceeded")
    healthy(s.url)


def test_slow_headers_and_slow_bodies_time_out(own_server):
    s = own_server(args=["--header-timeout", "2", "--min-body-rate-kib", "64"])
    # Headers one byte every 0.3 s: 408 at the 2 s deadline, although bytes keep coming.
    with connect(s.url) as sock:
        t = time.monotonic()
        answer = None
        for byte in b"GET /healthz HTTP/1.1\r\nHost: localhost\r\nX-Padding: " + b"a" * 100:
            try:
                sock.sendall(bytes([byte]))
            except OSError:
                break
            sock.settimeout(0.3)
            try:
                if sock.recv(1, socket.MSG_PEEK):
                    break
            except socket.timeout:
                continue
        answer = read_response(sock)
        elapsed = time.monotonic() - t
        problem_of(*answer, 408, "request_timeout")
        assert 1.5 < elapsed < 5, elapsed
    # A lying Content-Length: 1000 declared, 10 sent, then nothing: 408 after the grace.
    with connect(s.url) as sock:
        t = time.monotonic()
        sock.sendall(b"POST /v1/renders HTTP/1.1\r\nHost: x\r\nContent-Type: application/octet-stream\r\n"
                     b"Content-Length: 1000\r\n\r\nISO-10303-")
        p = problem_of(*read_response(sock), 408, "request_timeout")
        assert 1.5 < time.monotonic() - t < 5
        assert "KiB/s" in p["detail"]
    # A body trickling at 100 bytes/s (far below 64 KiB/s): cut off soon after the grace.
    with connect(s.url) as sock:
        t = time.monotonic()
        sock.sendall(b"POST /v1/renders HTTP/1.1\r\nHost: x\r\nContent-Type: application/octet-stream\r\n"
                     b"Content-Length: 100000\r\n\r\n")
        try:
            for _ in range(100):
                sock.sendall(b"x" * 10)
                time.sleep(0.1)
        except OSError:
            pass
        problem_of(*read_response(sock), 408, "request_timeout")
        assert time.monotonic() - t < 6
    healthy(s.url)


def test_oversized_headers(own_server):
    s = own_server()
    with connect(s.url) as sock:
        head = b"GET /healthz HTTP/1.1\r\nHost: x\r\n" + b"".join(
            b"X-Filler-%d: %s\r\n" % (i, b"a" * 4000) for i in range(20)) + b"\r\n"
        try:
            sock.sendall(head)
        except OSError:
            pass
        problem_of(*read_response(sock), 431, "limit_exceeded")
    healthy(s.url)


def test_slowloris_does_not_block_the_service(own_server):
    """30 connections sending one header byte every 0.5 s for 10 s (each lasts up
    to the default 10 s header deadline) on a service with few workers: the health
    probe, on new connections all the while, answers within 100 ms."""
    s = own_server(args=["--workers", "1", "--max-queue", "1"])
    stop = threading.Event()
    opened = []

    def slow_client():
        with connect(s.url) as sock:
            opened.append(1)
            for byte in b"GET /healthz HTTP/1.1\r\nHost: localhost\r\nX-Slow: " + b"z" * 1000:
                if stop.is_set():
                    return
                try:
                    sock.sendall(bytes([byte]))
                except OSError:
                    return
                stop.wait(0.5)

    clients = [threading.Thread(target=slow_client) for _ in range(30)]
    for c in clients:
        c.start()
    time.sleep(1)
    assert len(opened) == 30
    latencies = []
    t_end = time.monotonic() + 9
    while time.monotonic() < t_end:
        t = time.monotonic()
        r = requests.get(s.url + "/healthz", timeout=10)
        latencies.append(time.monotonic() - t)
        assert r.status_code == 200
        time.sleep(0.2)
    stop.set()
    for c in clients:
        c.join(timeout=30)
    slow = [x for x in latencies if x > 0.1]
    assert len(latencies) > 20
    # A shared CI machine may stall one probe; the old service blocked them all.
    assert len(slow) <= 1 and max(latencies) < 1, (len(latencies), sorted(latencies)[-5:])
    print(f"slowloris: {len(latencies)} probes, median {statistics.median(latencies) * 1000:.1f} ms, "
          f"max {max(latencies) * 1000:.1f} ms")


def test_connection_burst_all_answered(url):
    """64 connections at once: every one gets its answer. The listen backlog was 5
    (cpp-httplib's), and a burst beyond it got resets on a busy machine."""
    host, port = address(url)
    listening = subprocess.run(["ss", "-ltnH", f"sport = :{port}"], capture_output=True, text=True,
                               check=True).stdout.split()
    assert int(listening[2]) >= 128, listening  # LISTEN Recv-Q Send-Q(backlog) ...
    results = [None] * 64
    barrier = threading.Barrier(64)

    def one(i):
        barrier.wait()
        try:
            with connect(url) as sock:
                sock.sendall(b"GET /healthz HTTP/1.1\r\nHost: x\r\nConnection: close\r\n\r\n")
                results[i] = read_response(sock, timeout=30)[0]
        except OSError as e:
            results[i] = repr(e)

    threads = [threading.Thread(target=one, args=(i,)) for i in range(64)]
    for t in threads:
        t.start()
    for t in threads:
        t.join(timeout=60)
    assert results == [200] * 64, results


def test_connections_capped_per_client(own_server):
    s = own_server(args=["--max-connections-per-client", "4"])
    idle = [connect(s.url) for _ in range(4)]
    time.sleep(0.3)
    with connect(s.url) as sock:
        sock.sendall(b"GET /v1/jobs HTTP/1.1\r\nHost: x\r\n\r\n")
        status, headers, body = read_response(sock, timeout=5)
        problem_of(status, headers, body, 503, "overloaded")
        assert int(headers["retry-after"]) >= 1
    for sock in idle:
        sock.close()
    time.sleep(0.5)
    healthy(s.url)


@pytest.mark.parametrize("cap", [["--max-connections-per-client", "4"],
                                 ["--max-connections", "4", "--max-connections-per-client", "4"]],
                         ids=["per_client", "in_all"])
def test_health_probes_answered_beyond_the_connection_caps(own_server, cap):
    """Slow clients holding every connection (from one address, as behind a balancer, or in all) must not make
    the health probes fail: an orchestrator would restart a healthy instance. Probes beyond the caps are
    served in reserved slots, one request each; any other request there still gets 503."""
    s = own_server(args=cap)
    idle = [connect(s.url) for _ in range(4)]
    for sock in idle:
        sock.sendall(b"GET /healthz HTTP/1.1\r\nHost: x\r\nX-Slow: ")  # never finished
    time.sleep(0.3)
    for path in ("/healthz", "/readyz"):
        for method in ("GET", "HEAD"):
            t = time.monotonic()
            with connect(s.url) as sock:
                sock.sendall(f"{method} {path} HTTP/1.1\r\nHost: x\r\n\r\n".encode())
                status, headers, body = read_response(sock, timeout=5, no_body=method == "HEAD")
                assert status == 200, (method, path, status, body[:200])
                assert headers.get("connection") == "close"
            assert time.monotonic() - t < 2
    r = requests.get(s.url + "/healthz", timeout=5)
    assert r.status_code == 200
    with connect(s.url) as sock:
        sock.sendall(b"GET /v1/jobs HTTP/1.1\r\nHost: x\r\n\r\n")
        problem_of(*read_response(sock, timeout=5), 503, "overloaded")
    for sock in idle:
        sock.close()



def test_keep_alive_answers_without_delay(url):
    """Every answer on a kept-alive connection, not only the first, is prompt
    (Nagle's algorithm against the client's delayed ACK cost ~40 ms each)."""
    with requests.Session() as session:
        times = []
        for _ in range(20):
            t = time.monotonic()
            assert session.get(url + "/healthz", timeout=TIMEOUT).status_code == 200
            times.append(time.monotonic() - t)
    assert statistics.median(times[1:]) < 0.02, times


def test_long_target_problem_status(url):
    r = requests.get(url + "/v1/jobs?x=" + "a" * 9000, timeout=TIMEOUT)
    check_problem(r, 414)


def test_stop_right_after_start():
    """SIGTERM as soon as the port file appears (a supervisor's quick restart)
    stops the service promptly and cleanly, every time: the signal may come
    before the listening loop runs, and while the image writer's libraries are
    still being loaded."""
    for attempt in range(12):
        with tempfile.TemporaryDirectory() as tmp:
            port_file = pathlib.Path(tmp) / "port"
            with open(pathlib.Path(tmp) / "log", "wb") as log:
                proc = subprocess.Popen([os.environ["NURBSRT_BIN"], "serve", "--port", "0", "--port-file",
                                         str(port_file), "--data-dir", str(pathlib.Path(tmp) / "data")], stderr=log)
                deadline = time.monotonic() + 30
                while not (port_file.exists() and port_file.read_text().strip()):
                    assert time.monotonic() < deadline and proc.poll() is None, "server did not start"
                    time.sleep(0.001)
                proc.terminate()
                try:
                    rc = proc.wait(timeout=10)
                except subprocess.TimeoutExpired:
                    proc.kill()
                    proc.wait()
                    raise AssertionError(f"attempt {attempt}: SIGTERM right after the start went unheard")
            text = (pathlib.Path(tmp) / "log").read_text()
            assert rc == 0, (attempt, rc, text[-500:])
            assert '"event":"stopped"' in text, (attempt, text[-500:])


def test_stop_does_not_wait_for_slow_clients(own_server):
    """SIGTERM stops the service promptly although a client is still sending
    its headers (the header deadline is 10 s)."""
    s = own_server()
    with connect(s.url) as sock:
        sock.sendall(b"POST /v1/renders HTTP/1.1\r\nHost: x\r\nX-Slow: ")
        time.sleep(0.3)
        t = time.monotonic()
        s.proc.terminate()
        s.proc.wait(timeout=30)
        assert time.monotonic() - t < 3


# ---- hostile JSON: nesting, malformed text, size and value bounds ------------------------------------------
# The JSON of requests (a file_id body, options and job parts, PATCH of a stored file) is parsed with bounds:
# at most 64 levels deep, 256 KiB, 20,000 values; beyond them, or when it is no JSON at all, the answer is 400
# invalid_json. The recursive parser once overflowed the stack on a deep body and the whole process died
# (SIGSEGV), taking every request and running job with it.

ZERO_ID = "0" * 64


def deep(d):
    """A JSON array nested `d` levels deep: [[[...]]]."""
    return b"[" * d + b"]" * d


DEPTHS = (10_000, 60_000, 1_000_000)  # the 1M one is 2 MB: under the 4 MiB upload limit


def deep_request(base, entry, d):
    """One request whose JSON holds deep(d), sent to `entry` (see DEEP_ENTRIES)."""
    nested = deep(d)
    step = ("file", ("s.step", SCREW.read_bytes(), "application/octet-stream"))
    if entry == "render_json":
        return requests.post(base + "/v1/renders", data=b'{"file_id":"%s","x":%s}' % (ZERO_ID.encode(), nested),
                             headers={"Content-Type": "application/json"}, timeout=TIMEOUT)
    if entry == "render_options":
        return requests.post(base + "/v1/renders", timeout=TIMEOUT,
                             files=[step, ("options", (None, b'{"x":%s}' % nested, "application/json"))])
    if entry == "conversion_options":
        return requests.post(base + "/v1/conversions", timeout=TIMEOUT,
                             files=[step, ("options", (None, b'{"format":"stl","x":%s}' % nested,
                                                       "application/json"))])
    if entry == "job_outputs":
        return requests.post(base + "/v1/jobs", timeout=TIMEOUT,
                             files=[step, ("job", (None, b'{"outputs":%s}' % nested, "application/json"))])
    if entry == "job_output_options":
        spec = b'{"outputs":[{"file":0,"type":"render","options":{"x":%s}}]}' % nested
        return requests.post(base + "/v1/jobs", timeout=TIMEOUT,
                             files=[step, ("job", (None, spec, "application/json"))])
    if entry.startswith("patch_file:"):
        return requests.patch(f"{base}/v1/files/{entry.split(':', 1)[1]}", data=b'{"pinned":%s}' % nested,
                              headers={"Content-Type": "application/json"}, timeout=TIMEOUT)
    raise AssertionError(entry)


DEEP_ENTRIES = ["render_json", "render_options", "conversion_options", "job_outputs", "job_output_options",
                "patch_file"]


def stored_file_id(base):
    r = requests.post(base + "/v1/files", files=[("file", ("s.step", SCREW.read_bytes(), "application/octet-stream"))],
                      timeout=TIMEOUT)
    assert r.status_code in (200, 201), r.text[:300]
    return r.json()["id"]


def deep_outcome(server, entry, d):
    """None if the deep request is a 400 invalid_json naming the depth limit and the process still
    answers; else what happened instead."""
    try:
        r = deep_request(server.url, entry, d)
    except requests.ConnectionError as e:
        time.sleep(0.2)
        return f"no answer ({type(e).__name__}); the service's exit status: {server.proc.poll()} (-11: SIGSEGV)"
    try:
        p = check_problem(r, 400, "invalid_json")
        assert "64" in p["detail"], f"the detail does not name the limit: {p['detail']}"
        healthy(server.url)
    except (AssertionError, requests.ConnectionError, KeyError, ValueError):
        return f"{r.status_code} {r.text[:140]}"
    return None


@pytest.mark.parametrize("entry", DEEP_ENTRIES)
def test_deeply_nested_json_is_refused_not_a_crash(own_server, entry):
    """Every way JSON enters the service, 10k, 60k and 1M levels deep: 400 invalid_json, the service lives.
    Its own server: the old service died of it, and the shared one must outlive this test."""
    s = own_server(args=["--max-upload-mb", "4"])
    if entry == "patch_file":
        entry = "patch_file:" + stored_file_id(s.url)
    wrong = {}
    for d in DEPTHS:
        if s.proc.poll() is not None:
            break
        if (outcome := deep_outcome(s, entry, d)) is not None:
            wrong[d] = outcome
    assert not wrong, "; ".join(f"depth {d}: {what}" for d, what in wrong.items())
    assert s.proc.poll() is None


def test_deeply_nested_json_leaves_a_running_job_alone(own_server):
    """A job running while deep JSON arrives ends 'succeeded': the hostile request fails alone, it does not
    take the process (and so the job, 'interrupted' at the next start) with it."""
    s = own_server(args=["--max-upload-mb", "4", "--job-runners", "1", "--render-threads", "1"])
    spec = {"outputs": [{"file": 0, "type": "render", "options": SLOW_RENDER}]}
    r = requests.post(s.url + "/v1/jobs", timeout=TIMEOUT,
                      files=[("file", ("b.igs", BEARING.read_bytes(), "application/octet-stream")),
                             ("job", (None, json.dumps(spec), "application/json"))])
    assert r.status_code == 202, r.text[:300]
    job_url = f"{s.url}/v1/jobs/{r.json()['id']}"
    deadline = time.monotonic() + 60
    while requests.get(job_url, timeout=TIMEOUT).json()["outputs"][0]["state"] != "running":
        assert time.monotonic() < deadline, "the job never ran"
        time.sleep(0.05)
    for entry, d in (("render_json", 60_000), ("render_options", 60_000), ("job_outputs", 60_000),
                     ("render_json", 1_000_000)):
        assert (outcome := deep_outcome(s, entry, d)) is None, (entry, d, outcome)
    deadline = time.monotonic() + 120
    while (job := requests.get(job_url, timeout=TIMEOUT).json())["state"] not in ("succeeded", "failed"):
        assert time.monotonic() < deadline, json.dumps(job)[:600]
        time.sleep(0.1)
    assert job["state"] == "succeeded", json.dumps(job)[:600]


@pytest.mark.parametrize("body", [b'{"file_id":"ab', b'{"file_id": NaN}', b'{"file_id":"x","width":1e400}',
                                  b'{"file_id":"x"} xyz', b""],
                         ids=["truncated", "nan", "number_overflow", "trailing_garbage", "empty"])
def test_unparseable_json_body_is_invalid_json(url, body):
    """A body declared application/json that is no JSON (RFC 8259: no NaN, no trailing text; a number beyond
    a double is refused rather than read as infinity) is the client's malformed request, 400 invalid_json,
    not 415: its media type is supported. An empty one (Content-Length: 0) too."""
    r = requests.post(url + "/v1/renders", data=body, headers={"Content-Type": "application/json"},
                      timeout=TIMEOUT)
    if not body:
        assert r.request.headers["Content-Length"] == "0"
    check_problem(r, 400, "invalid_json")


def test_json_over_256_kib_is_invalid_json(url):
    """A JSON request body over 256 KiB (under the upload limit) is refused before it is parsed, naming the
    limit in bytes."""
    body = b'{"file_id":"%s","x":"%s"}' % (ZERO_ID.encode(), b"a" * 300_000)
    r = requests.post(url + "/v1/renders", data=body, headers={"Content-Type": "application/json"},
                      timeout=TIMEOUT)
    assert "262144" in check_problem(r, 400, "invalid_json")["detail"]


def test_json_with_too_many_values_is_invalid_json(url):
    """30,000 values in 60 KB (small, shallow, but each one a node to allocate): over the 20,000 values a
    request's JSON may hold."""
    body = b'{"file_id":"%s","x":[%s]}' % (ZERO_ID.encode(), b",".join([b"0"] * 30_000))
    assert len(body) < 256 << 10
    r = requests.post(url + "/v1/renders", data=body, headers={"Content-Type": "application/json"},
                      timeout=TIMEOUT)
    assert "20000" in check_problem(r, 400, "invalid_json")["detail"]


# ---- strict HTTP/1.1 framing (RFC 9112 §6) -----------------------------------------------------------------
# A request whose framing is ambiguous (two lengths, a length and a chunked body, a length that is no plain
# number, a header line that is no "name: value") could be read differently by a proxy in front of the
# service: request smuggling. Each is answered once (400 malformed_request, or 501 not_implemented for a
# transfer coding the service does not know) and the connection is closed, since where the next request
# would start is unknown. The old service answered the smuggled request too, and waited 10 s on unknown
# transfer codings.

def exchange_until_close(url, data, wait=3):
    """Sends `data` on a new connection and reads all that comes until the server closes it; returns (the
    first answer as read_response gives it, the bytes after it, seconds until its head arrived). Fails if
    nothing comes, or if the connection is still open `wait` seconds after the last bytes."""
    with connect(url) as sock:
        t = time.monotonic()
        try:
            sock.sendall(data)
        except OSError:
            pass  # the service answered and closed before taking everything: the answer is still there
        sock.settimeout(wait)
        received, elapsed = b"", None
        try:
            while chunk := sock.recv(65536):
                received += chunk
                if elapsed is None and b"\r\n\r\n" in received:
                    elapsed = time.monotonic() - t
        except ConnectionResetError:
            pass  # closed with unread bytes of ours: a close too
        except socket.timeout:
            raise AssertionError(f"the connection is still open {wait} s after {received[:300]!r}") from None
    assert elapsed is not None, f"closed without an answer: {received[:200]!r}"
    head, _, body = received.partition(b"\r\n\r\n")
    lines = head.decode("latin-1").split("\r\n")
    headers = {k.strip().lower(): v.strip() for k, v in (line.split(":", 1) for line in lines[1:])}
    length = int(headers.get("content-length", "0"))
    return (int(lines[0].split()[1]), headers, body[:length]), body[length:], elapsed


def refused_framing(url, data, status=400, code="malformed_request"):
    (st, headers, body), rest, elapsed = exchange_until_close(url, data)
    p = problem_of(st, headers, body, status, code)
    assert elapsed < 3, elapsed
    assert b"HTTP/1.1 " not in rest, f"a second answer on the connection: {rest[:300]!r}"
    return p


def test_framing_smuggled_request_is_not_answered(url):
    """A GET with a Content-Length whose body is a second request: one answer (400), never the /metrics one."""
    smuggled = b"GET /metrics HTTP/1.1\r\nHost: x\r\n\r\n"
    data = b"GET /healthz HTTP/1.1\r\nHost: x\r\nContent-Length: %d\r\n\r\n" % len(smuggled) + smuggled
    (st, headers, body), rest, _ = exchange_until_close(url, data)
    assert 1 + rest.count(b"HTTP/1.1 ") == 1, f"more answers than requests: {st} then {rest[:300]!r}"
    problem_of(st, headers, body, 400, "malformed_request")


def test_framing_head_with_a_body(url):
    """HEAD (like GET) has no body the service would read: the 5 bytes would be taken for the next request."""
    (st, headers, body), rest, elapsed = exchange_until_close(
        url, b"HEAD /healthz HTTP/1.1\r\nHost: x\r\nContent-Length: 5\r\n\r\nhello")
    assert st == 400 and elapsed < 3, (st, elapsed)
    if body:  # the answer to a HEAD may leave its body out
        problem_of(st, headers, body, 400, "malformed_request")
    assert b"HTTP/1.1 " not in rest, rest[:300]


def test_framing_get_with_content_length_zero_is_fine(url):
    """Content-Length: 0 on a GET frames no body: no reason to refuse it or to close the connection."""
    with connect(url) as sock:
        sock.sendall(b"GET /healthz HTTP/1.1\r\nHost: x\r\nContent-Length: 0\r\n\r\n")
        st, headers, _ = read_response(sock, timeout=3)
        assert st == 200 and headers.get("connection") != "close", (st, headers)
        sock.sendall(b"GET /healthz HTTP/1.1\r\nHost: x\r\n\r\n")
        assert read_response(sock, timeout=3)[0] == 200


POST_HEAD = b"POST /v1/renders HTTP/1.1\r\nHost: x\r\nContent-Type: application/octet-stream\r\n"


@pytest.mark.parametrize("lengths", [[b"+10"], [b"1, 1"], [b"10", b"11"], [b"10", b"10"]],
                         ids=["plus_sign", "list", "two_different", "two_same"])
def test_framing_content_length_not_one_plain_number(url, lengths):
    """Content-Length is 1*DIGIT, once: a sign, a list or a repeated header (even with the same value,
    which a proxy may have joined or not) is no length to trust."""
    head = POST_HEAD + b"".join(b"Content-Length: %s\r\n" % v for v in lengths) + b"\r\n"
    refused_framing(url, head + b"0123456789")


@pytest.mark.parametrize("coding", [b"xchunked", b"gzip, chunked", b"chunked, identity"])
def test_framing_unknown_transfer_coding_is_501(url, coding):
    """Only "chunked" alone is understood: for any other transfer coding the body's end is unknown, so the
    answer is 501 at once (not a 408 after waiting for a body that never ends) and the connection closes."""
    refused_framing(url, POST_HEAD + b"Transfer-Encoding: %s\r\n\r\n0\r\n\r\n" % coding, 501, "not_implemented")


def test_framing_chunked_and_content_length(url):
    refused_framing(url, POST_HEAD + b"Transfer-Encoding: chunked\r\nContent-Length: 10\r\n\r\n0\r\n\r\n")


@pytest.mark.parametrize("lines", [b"Host: x\r\nX-Bad-Line\r\n", b"Host : x\r\n", b"Host: x\r\nX-A : a\r\n",
                                   b"Host: x\r\nX-A: a\r\n folded\r\n", b"Host: x\nX-A: a\r\n"],
                         ids=["no_colon", "space_before_colon_host", "space_before_colon", "obs_fold", "bare_lf"])
def test_framing_malformed_header_line(url, lines):
    """RFC 9112 §5.1/§5.2/§2.2: a field line without a colon, whitespace before the colon, a folded line and
    a line ended by a bare LF are each read differently by different parsers: 400."""
    refused_framing(url, b"GET /healthz HTTP/1.1\r\n" + lines + b"\r\n")


@pytest.mark.parametrize("hosts", [b"", b"Host: x\r\nHost: y\r\n"], ids=["none", "two"])
def test_framing_http11_needs_exactly_one_host(url, hosts):
    refused_framing(url, b"GET /healthz HTTP/1.1\r\n" + hosts + b"\r\n")
    # HTTP/1.0 predates Host: none is fine.
    (st, _, _), _, _ = exchange_until_close(url, b"GET /healthz HTTP/1.0\r\n\r\n")
    assert st == 200


# ---- Keep-Alive announces the real limits -------------------------------------------------------------------

def test_keep_alive_header_tells_the_real_request_limit(url):
    """A connection serves 100 requests: the 100th answer closes it, and every Keep-Alive header before
    says max=100 (or the requests left), not a number the service does not keep to (it said max=5)."""
    limit = 100
    with connect(url) as sock:
        for n in range(1, limit + 1):
            sock.sendall(b"GET /healthz HTTP/1.1\r\nHost: x\r\n\r\n")
            st, headers, _ = read_response(sock, timeout=5)
            assert st == 200
            closing = headers.get("connection", "").lower() == "close"
            if n < limit:
                assert not closing, f"answer {n} closed the connection"
                if "keep-alive" in headers:
                    params = dict(p.strip().partition("=")[::2] for p in headers["keep-alive"].split(","))
                    assert int(params["max"]) in (limit, limit - n + 1, limit - n), (n, headers["keep-alive"])
        if not closing:  # the 100th answer may leave the close unsaid, but then the connection must end
            sock.settimeout(3)
            try:
                sock.sendall(b"GET /healthz HTTP/1.1\r\nHost: x\r\n\r\n")
                assert sock.recv(65536) == b"", "a 101st request answered"
            except (ConnectionResetError, BrokenPipeError):
                pass
