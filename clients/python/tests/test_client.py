"""The client package against a live service (NURBSRT_URL; NURBSRT_API_KEY if it needs one).
Run by tests/api/test_python_client.py in a venv where the package is pip-installed."""
import hashlib
import hmac
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


def test_job_with_progress_and_artifacts(client, tmp_path):
    variant = tmp_path / "screw-copy.step"
    # Other bytes, the same part: a newline count no other test of the service uses.
    variant.write_bytes(SCREW.read_bytes() + b"\n" * 3911)
    outputs = []
    for f in range(3):
        outputs += [{"file": f, "type": "render", "options": {"width": 80, "height": 60}},
                    {"file": f, "type": "conversion", "format": "stl"},
                    {"file": f, "type": "conversion", "format": "glb"}]
    job = client.submit_job([SCREW, BEARING, variant], outputs, force=True)
    seen = []
    final = client.wait(job["id"], progress=seen.append, interval=0.05, timeout=300)
    assert final["state"] == "succeeded", final
    assert seen and seen[-1]["state"] == "succeeded"
    progress = [j["progress"] for j in seen]
    assert progress == sorted(progress) and progress[-1] == 1, progress
    done = [sum(o["state"] == "succeeded" for o in j["outputs"]) for j in seen]
    assert done == sorted(done) and done[-1] == 9, done
    for out in final["outputs"]:
        data = client.download(out, tmp_path / out["artifact"]["name"])
        assert len(data) == out["artifact"]["bytes"] > 0
    assert {o["format"] for o in final["outputs"]} == {"png", "stl", "glb"}


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
