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

import requests

from conftest import SCREW, TIMEOUT, check_problem, healthy, post_raw, validate


def address(url):
    u = urlparse(url)
    return u.hostname, u.port


def read_response(sock, timeout=15):
    """(status, headers dict with lower-case names, body bytes) of one HTTP/1.1 answer."""
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
    length = int(headers.get("content-length", "0"))
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
        ({"Content-Length": "12abc"}, 400, "invalid_argument"),
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
        sock.sendall(b"GET /healthz HTTP/1.1\r\nHost: x\r\n\r\n")
        status, headers, body = read_response(sock, timeout=5)
        problem_of(status, headers, body, 503, "overloaded")
        assert int(headers["retry-after"]) >= 1
    for sock in idle:
        sock.close()
    time.sleep(0.5)
    healthy(s.url)


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
