"""GET /v1/jobs/{id}/events: a job's events as Server-Sent Events, read here with raw sockets
and requests (the Python client's use of them is in clients/python/tests)."""
import json
import os
import signal
import socket
import subprocess
import time
import urllib.parse

import pytest
import requests

from conftest import BEARING, PG_ADMIN, SCREW, SLOW_RENDER, TIMEOUT, check_problem, validate
from test_jobs import accepted, submit, wait_finished

# Variants of the screw with newline counts no other test draws: other bytes, the same part
# (a job's outputs are then no cache or artifact reuse hits of other tests).
NEWLINES = 4127


def screw_variant(extra):
    return SCREW.read_bytes() + b"\n" * (NEWLINES + extra)


def three_outputs(f):
    return [{"file": f, "type": "render", "options": {"width": 64, "height": 48}},
            {"file": f, "type": "conversion", "format": "stl"},
            {"file": f, "type": "conversion", "format": "brep"}]


class RawStream:
    """An event stream over a raw socket: the request as written, the chunked answer decoded by hand."""

    def __init__(self, base, job_id, headers=(), query=""):
        u = urllib.parse.urlparse(base)
        self.sock = socket.create_connection((u.hostname, u.port), timeout=60)
        head = f"GET /v1/jobs/{job_id}/events{query} HTTP/1.1\r\nHost: {u.hostname}\r\n"
        head += "".join(f"{k}: {v}\r\n" for k, v in headers) + "\r\n"
        self.sock.sendall(head.encode())
        self.buf = b""
        status_and_headers = self._until(b"\r\n\r\n").decode()
        lines = status_and_headers.split("\r\n")
        self.status = int(lines[0].split()[1])
        self.headers = {k.lower(): v.strip() for k, _, v in (line.partition(":") for line in lines[1:])}
        self.text = ""
        self.parsed = []  # events read but not yet taken
        self.ended = False

    def _until(self, sep):
        while sep not in self.buf:
            data = self.sock.recv(65536)
            if not data:
                raise EOFError("connection closed")
            self.buf += data
        out, self.buf = self.buf.split(sep, 1)
        return out

    def _chunk(self):
        size = int(self._until(b"\r\n").split(b";")[0], 16)
        while len(self.buf) < size + 2:
            data = self.sock.recv(65536)
            if not data:
                raise EOFError("connection closed in a chunk")
            self.buf += data
        chunk, self.buf = self.buf[:size], self.buf[size + 2:]
        if size == 0:
            self.ended = True
        return chunk.decode()

    def events(self, count=None):
        """Events as (id, type, data) until `count` of them or the stream's end."""
        while not self.ended and (count is None or len(self.parsed) < count):
            self.text += self._chunk()
            while "\n\n" in self.text:
                block, self.text = self.text.split("\n\n", 1)
                fields = [line.partition(": ") for line in block.split("\n") if not line.startswith(":")]
                if fields:
                    d = {k: v for k, _, v in fields}
                    assert set(d) == {"id", "event", "data"}, block
                    self.parsed.append((int(d["id"]), d["event"], json.loads(d["data"])))
        n = len(self.parsed) if count is None else count
        out, self.parsed = self.parsed[:n], self.parsed[n:]
        return out

    def close(self):
        self.sock.close()


def all_events(base, job_id, **params):
    """Every event of a finished job, read with requests (the stream ends after the terminal one)."""
    r = requests.get(f"{base}/v1/jobs/{job_id}/events", params=params, timeout=TIMEOUT)
    assert r.status_code == 200, r.text[:300]
    assert r.headers["Content-Type"].startswith("text/event-stream")
    out = []
    for block in r.text.split("\n\n"):
        d = dict(line.partition(": ")[::2] for line in block.split("\n") if line and not line.startswith(":"))
        if d:
            out.append((int(d["id"]), d["event"], json.loads(d["data"])))
    return out


def check_sequence(events, outputs):
    """The events of a job of `outputs` outputs that succeeded: in order, each once, terminal last."""
    assert [e[0] for e in events] == list(range(1, len(events) + 1)), [e[0] for e in events]
    assert events[0][1:] == ("state", {"state": "queued"})
    assert events[-1][1] == "state" and events[-1][2]["state"] == "succeeded"
    for _, kind, data in events:
        validate(data, {"state": "JobStateEvent", "output": "JobOutputEvent", "artifact": "JobArtifactEvent",
                        "progress": "JobProgressEvent"}[kind])
    done = [d["outputs_done"] for _, k, d in events if k == "progress"]
    assert done == sorted(done) and done[-1] == outputs and all(
        d["outputs_total"] == outputs for _, k, d in events if k == "progress")
    artifacts = [d for _, k, d in events if k == "artifact"]
    assert sorted(a["output"] for a in artifacts) == list(range(outputs))
    for i in range(outputs):
        states = [d["state"] for _, k, d in events if k == "output" and d["output"] == i]
        assert states[-1] == "succeeded" and "running" in states, (i, states)
        finished = next(n for n, (_, k, d) in enumerate(events) if k == "output" and d["output"] == i
                        and d["state"] == "succeeded")
        assert events[finished][2]["duration_ms"] >= 0
        assert events[finished + 1][1] == "artifact" and events[finished + 1][2]["output"] == i
    return artifacts


def test_events_in_order_resume_raw_and_downloads(url):
    files = [(f"v{i}.step", screw_variant(i)) for i in range(3)]
    job = accepted(submit(url, files, {"outputs": three_outputs(0) + three_outputs(1) + three_outputs(2),
                                       "force": True}))
    first = RawStream(url, job["id"])
    assert first.status == 200 and first.headers["content-type"].startswith("text/event-stream")
    assert first.headers["cache-control"] == "no-store"
    head = first.events(3)
    first.close()  # the client goes away mid-job ...
    assert [e[0] for e in head] == [1, 2, 3]
    # ... and comes back with the last id it saw: it gets exactly the rest, to the terminal event.
    again = RawStream(url, job["id"], headers=[("Last-Event-ID", str(head[-1][0]))])
    rest = again.events()
    again.close()
    assert again.ended and rest[0][0] == head[-1][0] + 1
    full = all_events(url, job["id"])
    assert head + rest == full
    artifacts = check_sequence(full, 9)
    for a in artifacts:
        r = requests.get(url + a["url"], timeout=TIMEOUT)
        assert r.status_code == 200 and len(r.content) == a["bytes"] > 0
        assert r.headers["Content-Type"] == a["content_type"]
    # The query parameter resumes the same way; past the terminal event the stream is empty and ends.
    assert all_events(url, job["id"], last_event_id=len(full) - 2) == full[-2:]
    assert all_events(url, job["id"], last_event_id=len(full)) == []


def test_bad_last_event_id_and_unknown_job(url):
    job = accepted(submit(url, [("b.iges", BEARING.read_bytes())],
                          {"outputs": [{"file": 0, "type": "conversion", "format": "brep"}]}))
    r = requests.get(f"{url}/v1/jobs/{job['id']}/events", headers={"Last-Event-ID": "x1"}, timeout=TIMEOUT)
    assert "Last-Event-ID" in check_problem(r, 400, "invalid_argument")["detail"]
    r = requests.get(f"{url}/v1/jobs/{job['id']}/events", params={"last_event_id": "-1"}, timeout=TIMEOUT)
    assert "last_event_id" in check_problem(r, 400, "invalid_argument")["detail"]
    check_problem(requests.get(f"{url}/v1/jobs/{'0' * 32}/events", timeout=TIMEOUT), 404, "not_found")
    check_problem(requests.get(f"{url}/v1/jobs/..%2F/events", timeout=TIMEOUT), 404)
    wait_finished(url, job["id"])


def slow_job(base, extra):
    return accepted(submit(base, [("slow.step", screw_variant(extra))],
                           {"outputs": [{"file": 0, "type": "render", "options": SLOW_RENDER}] * 3, "force": True}))


def test_stream_cap_is_503_and_frees_on_close(own_server):
    s = own_server(args=["--max-event-streams", "1"])
    job = slow_job(s.url, 10)
    held = RawStream(s.url, job["id"])
    assert held.status == 200 and held.events(1)[0][1] == "state"
    r = requests.get(f"{s.url}/v1/jobs/{job['id']}/events", timeout=TIMEOUT)
    check_problem(r, 503, "overloaded")
    assert int(r.headers["Retry-After"]) > 0
    assert requests.get(f"{s.url}/v1/jobs/{job['id']}", timeout=TIMEOUT).status_code == 200  # requests still served
    metrics = requests.get(s.url + "/metrics", timeout=TIMEOUT).text
    assert "\nnurbsrt_event_streams 1\n" in metrics and "\nnurbsrt_event_streams_max 1\n" in metrics
    held.close()
    deadline = time.monotonic() + 10
    while True:  # the slot frees once the server notices the closed connection (within a poll)
        again = RawStream(s.url, job["id"])
        if again.status == 200:
            break
        again.close()
        assert time.monotonic() < deadline, "the stream's slot was never freed"
        time.sleep(0.2)
    again.close()


def test_max_event_streams_must_leave_connections(tmp_path):
    r = subprocess.run([os.environ["NURBSRT_BIN"], "serve", "--port", "0", "--data-dir", str(tmp_path / "data"),
                        "--max-connections", "4", "--max-connections-per-client", "4", "--max-event-streams", "4"],
                       capture_output=True, text=True, timeout=60, stdin=subprocess.DEVNULL)
    assert r.returncode != 0 and "max event streams" in r.stderr, r.stderr


def test_events_need_the_key(own_server):
    key = "k" * 24
    s = own_server(env={"NURBSRT_API_KEYS": key})
    auth = {"Authorization": f"Bearer {key}"}
    r = requests.post(s.url + "/v1/jobs", headers=auth, timeout=TIMEOUT, files=[
        ("file", ("b.iges", BEARING.read_bytes(), "application/octet-stream")),
        ("job", (None, json.dumps({"outputs": [{"file": 0, "type": "conversion", "format": "brep"}]}),
                 "application/json"))])
    job = accepted(r)
    check_problem(requests.get(f"{s.url}/v1/jobs/{job['id']}/events", timeout=TIMEOUT), 401)
    r = requests.get(f"{s.url}/v1/jobs/{job['id']}/events", headers=auth, timeout=TIMEOUT)
    assert r.status_code == 200 and "event: state" in r.text


def test_streams_end_at_shutdown(own_server):
    s = own_server()
    job = slow_job(s.url, 20)
    stream = RawStream(s.url, job["id"])
    assert stream.events(1)
    t0 = time.monotonic()
    s.proc.send_signal(signal.SIGTERM)
    try:
        stream.events()  # ends: the last chunk, or the connection closed
    except EOFError:
        pass
    stream.close()
    assert s.proc.wait(timeout=30) == 0
    assert time.monotonic() - t0 < 30


@pytest.mark.skipif(not PG_ADMIN, reason="PostgreSQL only (tests/api_postgres.sh): two instances on one job store")
def test_events_of_one_instance_streamed_by_another(own_server, tmp_path):
    a = own_server(data_dir=tmp_path / "shared")
    b = own_server(data_dir=tmp_path / "shared")
    files = [(f"p{i}.step", screw_variant(30 + i)) for i in range(3)]
    job = accepted(submit(a.url, files, {"outputs": three_outputs(0) + three_outputs(1) + three_outputs(2),
                                         "force": True}))
    on_b = RawStream(b.url, job["id"])  # the job was accepted by a: its first event is a's
    head = on_b.events(2)
    on_b.close()
    rest = RawStream(a.url, job["id"], headers=[("Last-Event-ID", str(head[-1][0]))]).events()
    full_b = all_events(b.url, job["id"])
    assert head + rest == full_b == all_events(a.url, job["id"])
    check_sequence(full_b, 9)
