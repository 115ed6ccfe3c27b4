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


def test_keys_configured_but_empty_refuses_to_start(tmp_path):
    """Auth fails closed: a keys file without a key (only a comment, empty: a
    secret that did not get mounted) or an empty NURBSRT_API_KEYS stops the start
    instead of serving everything unauthenticated."""
    import os
    import subprocess
    keys = tmp_path / "keys"
    cases = [("# only a comment\n\n   \n", None), ("", None), (None, ""), (None, " , ,")]
    for text, env_keys in cases:
        args = [os.environ["NURBSRT_BIN"], "serve", "--port", "0", "--data-dir", str(tmp_path / "d")]
        env = {k: v for k, v in os.environ.items() if k != "NURBSRT_API_KEYS"}
        if text is not None:
            keys.write_text(text)
            args += ["--api-keys-file", str(keys)]
        if env_keys is not None:
            env["NURBSRT_API_KEYS"] = env_keys
        p = subprocess.run(args, capture_output=True, text=True, timeout=60, env=env)
        assert p.returncode != 0, (text, env_keys, p.stderr[-300:])
        assert "holds no key" in p.stderr and "refusing to start without authentication" in p.stderr, p.stderr


def test_no_keys_configured_needs_none(url):
    r = requests.get(url + "/metrics", timeout=TIMEOUT)
    assert r.status_code == 200
