"""Optional API keys: with keys configured, every route but the probes and the
API document answers 401 (problem+json, WWW-Authenticate) without a valid
bearer key, before any work; with a key from the file or the environment it works."""
import pathlib

import requests

from conftest import SCREW, TIMEOUT, check_problem, healthy, post_raw

KEY_A = "test-key-aaaaaaaaaaaaaaaa-0001"
KEY_B = "test-key-bbbbbbbbbbbbbbbb-0002"


def test_keys_from_file_and_environment(own_server, tmp_path):
    keys = tmp_path / "keys"
    keys.write_text(f"# keys of the API tests\n\n{KEY_A}\n")
    s = own_server(args=["--api-keys-file", str(keys)], env={"NURBSRT_API_KEYS": KEY_B})
    data = SCREW.read_bytes()
    params = {"width": 64, "height": 48}

    r = post_raw(s.url, "/v1/renders", data, params)
    check_problem(r, 401, "unauthorized")
    assert r.headers["WWW-Authenticate"].startswith("Bearer")
    for wrong in (f"Bearer {KEY_A}x", f"Bearer {KEY_A[:-1]}", "Bearer ", KEY_A, f"Basic {KEY_A}"):
        check_problem(post_raw(s.url, "/v1/renders", data, params, {"Authorization": wrong}), 401, "unauthorized")
    check_problem(requests.get(s.url + "/metrics", timeout=TIMEOUT), 401, "unauthorized")
    # An unknown route is not revealed to an unauthenticated client either.
    check_problem(requests.get(s.url + "/v1/nothing", timeout=TIMEOUT), 401, "unauthorized")

    # The probes and the API document stay open (container health checks, clients' codegen).
    healthy(s.url)
    assert requests.get(s.url + "/readyz", timeout=TIMEOUT).status_code == 200
    assert requests.get(s.url + "/v1/openapi.json", timeout=TIMEOUT).json()["openapi"].startswith("3.1")

    for key, scheme in ((KEY_A, "Bearer"), (KEY_B, "bearer")):
        r = post_raw(s.url, "/v1/renders", data, params, {"Authorization": f"{scheme} {key}"})
        assert r.status_code == 200, r.text[:300]
        assert r.headers["Content-Type"] == "image/png"
    r = requests.get(s.url + "/metrics", headers={"Authorization": f"Bearer {KEY_A}"}, timeout=TIMEOUT)
    assert r.status_code == 200
    assert 'status="401"' in r.text  # the rejected requests were counted
    # The keys never reach the log.
    s.log.flush()
    log = pathlib.Path(s.log.name).read_text(errors="replace")
    assert KEY_A not in log and KEY_B not in log


def test_short_key_refuses_to_start(tmp_path):
    import os
    import subprocess
    keys = tmp_path / "keys"
    keys.write_text("short\n")
    p = subprocess.run([os.environ["NURBSRT_BIN"], "serve", "--port", "0", "--data-dir", str(tmp_path / "d"),
                        "--api-keys-file", str(keys)], capture_output=True, text=True, timeout=60)
    assert p.returncode != 0
    assert "shorter than 16 characters" in p.stderr


def test_no_keys_configured_needs_none(url):
    r = requests.get(url + "/metrics", timeout=TIMEOUT)
    assert r.status_code == 200
