"""The client package against a live service (NURBSRT_URL; NURBSRT_API_KEY if it needs one).
Run by tests/api/test_python_client.py in a venv where the package is pip-installed."""
import hashlib
import hmac
import json
import os
import pathlib
import subprocess
import sys

import pytest

from nurbsrt_client import (Client, InvalidRequest, NotFound, Unavailable, Unprocessable, error_for,
                            verify_signature)

URL = os.environ["NURBSRT_URL"]
DATA = pathlib.Path("/usr/share/opencascade/data")
SCREW = DATA / "step" / "screw.step"
BEARING = DATA / "iges" / "bearing.iges"
PNG = b"\x89PNG\r\n\x1a\n"


@pytest.fixture(scope="module")
def client():
    return Client(URL, api_key=os.environ.get("NURBSRT_API_KEY"))


def test_upload_list_render_by_id_and_by_path(client):
    stored = client.upload(SCREW)
    assert stored["id"] == hashlib.sha256(SCREW.read_bytes()).hexdigest()
    assert any(f["id"] == stored["id"] for f in client.files())
    by_id = client.render(stored["id"], width=96, height=72, view="top")
    by_path = client.render(SCREW, width=96, height=72, view="top")
    assert by_id.image.startswith(PNG) and by_id.content_type == "image/png"
    assert by_id.statistics["pixels_hit"] > 0 and by_id.statistics["pixels_hit"] == by_path.statistics["pixels_hit"]
    assert by_id.statistics["cache"] == "hit"  # stored files are imported when stored
    sheet = client.render(stored["id"], width=64, height=48, views=["front", "iso"], layout="separate")
    assert list(sheet.images) == ["front", "iso"] and all(i.startswith(PNG) for i in sheet.images.values())


def test_convert(client):
    stl = client.convert(SCREW, "stl")
    assert stl.content_type == "model/stl" and len(stl.data) > 84 and stl.report["faces"] > 0
    assert "fidelity" in stl.report


def test_problems_are_typed_exceptions(client):
    with pytest.raises(Unprocessable) as e:
        client.render(b"not a CAD file\n")
    assert e.value.status == 415 and e.value.code == "unsupported_format" and e.value.request_id
    with pytest.raises(InvalidRequest) as e:
        client.render(SCREW, width=0)
    assert e.value.code == "invalid_argument" and "width" in e.value.detail
    with pytest.raises(NotFound):
        client.file("0" * 64)


def nine_outputs():
    outputs = []
    for f in range(3):
        outputs += [{"file": f, "type": "render", "options": {"width": 80, "height": 60}},
                    {"file": f, "type": "conversion", "format": "stl"},
                    {"file": f, "type": "conversion", "format": "glb"}]
    return outputs


def variant(tmp_path, newlines):
    """Other bytes, the same part: a newline count no other test of the service uses."""
    path = tmp_path / f"screw-{newlines}.step"
    path.write_bytes(SCREW.read_bytes() + b"\n" * newlines)
    return path


def test_job_with_progress_and_artifacts(client, tmp_path):
    job = client.submit_job([SCREW, BEARING, variant(tmp_path, 3911)], nine_outputs(), force=True)
    seen = []
    final = client.wait(job["id"], progress=seen.append, interval=0.05, timeout=300)
    assert final["state"] == "succeeded", final
    assert seen and seen[-1].state == "succeeded" and seen[-1].event.terminal
    fractions = [p.fraction for p in seen]
    assert fractions == sorted(fractions) and fractions[-1] == 1, fractions
    done = [p.outputs_done for p in seen]
    assert done == sorted(done) and done[-1] == 9 and all(p.outputs_total == 9 for p in seen), done
    assert [p.event.id for p in seen] == sorted({p.event.id for p in seen})  # in order, each once
    for out in final["outputs"]:
        data = client.download(out, tmp_path / out["artifact"]["name"])
        assert len(data) == out["artifact"]["bytes"] > 0
    assert {o["format"] for o in final["outputs"]} == {"png", "stl", "glb"}


def test_job_events_in_order_then_artifacts_downloaded(client, tmp_path):
    job = client.submit_job([SCREW, BEARING, variant(tmp_path, 4127)], nine_outputs(), force=True)
    events = list(client.events(job["id"]))
    assert [e.id for e in events] == list(range(1, len(events) + 1))
    assert (events[0].type, events[0].data) == ("state", {"state": "queued"})
    assert events[-1].terminal and events[-1].data["state"] == "succeeded"
    assert sum(e.terminal for e in events) == 1
    for i in range(9):
        mine = [e for e in events if e.data.get("output") == i and e.type in ("output", "artifact")]
        assert [(e.type, e.data.get("state")) for e in mine] == [("output", "running"), ("output", "succeeded"),
                                                                  ("artifact", None)], mine
        assert mine[1].data["duration_ms"] == mine[1].data["finished_ms"] - mine[1].data["started_ms"] >= 0
    progress = [e.data for e in events if e.type == "progress"]
    assert [p["outputs_done"] for p in progress] == sorted(p["outputs_done"] for p in progress)
    assert progress[-1]["outputs_done"] == progress[-1]["outputs_total"] == 9 and progress[-1]["fraction"] == 1
    bytes_written = 0
    for e in events:
        if e.type == "artifact":  # downloadable as soon as its event came
            data = client.download(e.data["url"], tmp_path / e.data["name"])
            assert len(data) == e.data["bytes"] > 0
            bytes_written += len(data)
    assert progress[-1]["artifact_bytes"] == bytes_written


def test_events_resume_after_last_event_id(client, tmp_path):
    job = client.submit_job([variant(tmp_path, 4129)], nine_outputs()[:3], force=True)
    stream = client.events(job["id"])
    head = [next(stream) for _ in range(3)]
    stream.close()  # the client goes away mid-job
    rest = list(client.events(job["id"], last_event_id=head[-1].id))
    assert rest[0].id == head[-1].id + 1 and rest[-1].terminal
    assert head + rest == list(client.events(job["id"]))  # nothing missed, nothing twice


class DroppingResponse:
    """An event stream that breaks after its lines (as a dropped connection does) unless it is the last."""

    def __init__(self, lines, drop):
        self.status_code, self.headers, self.text, self.lines, self.drop = 200, {}, "", lines, drop

    def iter_lines(self, decode_unicode=True):
        yield from self.lines
        if self.drop:
            import requests
            raise requests.exceptions.ChunkedEncodingError("connection broken")

    def close(self):
        pass


class DroppingSession:
    def __init__(self):
        self.headers, self.sent = {}, []

    def request(self, method, url, timeout=None, headers=None, **kw):
        self.sent.append(dict(headers or {}))
        if len(self.sent) == 1:
            return DroppingResponse(["id: 1", "event: state", 'data: {"state":"queued"}', "", ": keep-alive", "",
                                     "id: 2", "event: state", 'data: {"state":"running"}', ""], drop=True)
        return DroppingResponse(["id: 3", "event: state", 'data: {"state":"succeeded"}', ""], drop=False)


def test_events_reconnect_with_last_event_id_when_dropped(monkeypatch):
    import nurbsrt_client.client as module
    monkeypatch.setattr(module, "EVENT_RECONNECT_WAIT_S", 0.01)
    session = DroppingSession()
    got = list(Client("http://127.0.0.1:9", session=session).events("a" * 32))
    assert [(e.id, e.data["state"]) for e in got] == [(1, "queued"), (2, "running"), (3, "succeeded")]
    assert "Last-Event-ID" not in session.sent[0] and session.sent[1]["Last-Event-ID"] == "2"


class BusyStreamSession:
    """The job document, 503 for its events stream (the service's stream cap is reached), then the job done."""

    def __init__(self):
        self.headers, self.paths, self.polls = {}, [], 0

    def request(self, method, url, timeout=None, headers=None, **kw):
        self.paths.append(url.split("/v1/")[1])
        if url.endswith("/events"):
            return FakeResponse(503, {"Retry-After": "1"}, {"code": "overloaded", "title": "Busy"})
        self.polls += 1
        state = "running" if self.polls < 3 else "succeeded"
        outputs = [{"state": "succeeded" if state == "succeeded" else "running"}]
        return FakeResponse(200, {}, {"id": "j", "state": state, "outputs": outputs})


def test_wait_polls_when_the_service_refuses_a_stream():
    session = BusyStreamSession()
    seen = []
    job = Client("http://127.0.0.1:9", session=session).wait("a" * 32, progress=seen.append, interval=0.01)
    assert job["state"] == "succeeded"
    assert session.paths.count(f"jobs/{'a' * 32}/events") == 1  # not retried: polling serves at once
    assert [(p.state, p.outputs_done, p.outputs_total) for p in seen] == [("running", 0, 1), ("succeeded", 1, 1)]
    assert all(p.event is None for p in seen)


def test_cli_job_prints_progress_and_downloads(tmp_path):
    out = tmp_path / "out"
    r = subprocess.run([sys.executable, "-m", "nurbsrt_client.cli", "--url", URL, "job", str(variant(tmp_path, 4131)),
                        "--render", "width=64,height=48", "--convert", "stl", "-d", str(out)],
                       capture_output=True, text=True, timeout=300,
                       env=dict(os.environ, NURBSRT_API_KEY=os.environ.get("NURBSRT_API_KEY", "")))
    assert r.returncode == 0, r.stderr
    assert "100% (2/2 outputs" in r.stderr and "succeeded" in r.stderr, r.stderr
    job = json.loads(r.stdout)
    assert sorted(p.name for p in out.iterdir()) == sorted(o["artifact"]["name"] for o in job["outputs"])


class FakeResponse:
    def __init__(self, status, headers=None, body=None):
        self.status_code, self.headers, self._body, self.text = status, headers or {}, body, ""

    def json(self):
        if self._body is None:
            raise ValueError("no body")
        return self._body


class FakeSession:
    """Answers 503 with Retry-After, then 200: the client waits and sends again."""

    def __init__(self):
        self.headers, self.calls = {}, 0

    def request(self, method, url, timeout=None, **kw):
        self.calls += 1
        if self.calls == 1:
            return FakeResponse(503, {"Retry-After": "0.2"}, {"code": "unavailable", "title": "Busy"})
        return FakeResponse(200, body={"id": "x", "state": "queued"})


def test_busy_answers_are_retried_after_retry_after():
    session = FakeSession()
    c = Client("http://unused", session=session)
    assert c.job("x")["state"] == "queued" and session.calls == 2
    c = Client("http://unused", session=FakeSession(), retries=0)
    with pytest.raises(Unavailable):
        c.job("x")
    assert isinstance(error_for(422, {"code": "strict_refused"}), Unprocessable)


def test_webhook_signature():
    body = b'{"id": "abc", "state": "succeeded"}'
    good = "sha256=" + hmac.new(b"0123456789abcdef", body, hashlib.sha256).hexdigest()
    assert verify_signature("0123456789abcdef", body, good)
    assert not verify_signature("0123456789abcdef", body + b" ", good)
    assert not verify_signature("0123456789abcdef", body, None)


def test_console_script(tmp_path):
    out = tmp_path / "screw.png"
    script = pathlib.Path(sys.executable).parent / "nurbsrt-client"
    env = dict(os.environ)
    r = subprocess.run([str(script), "--url", URL, "render", str(SCREW), "-o", str(out), "--view", "iso",
                        "--width", "64", "--height", "48", "--option", "edges=true"],
                       capture_output=True, text=True, env=env, timeout=120)
    assert r.returncode == 0, r.stderr
    assert out.read_bytes().startswith(PNG)
    r = subprocess.run([str(script), "--url", URL, "render", str(SCREW), "-o", str(out), "--option", "width=0"],
                       capture_output=True, text=True, env=env, timeout=120)
    assert r.returncode == 1 and "invalid_argument" in r.stderr, r.stderr
