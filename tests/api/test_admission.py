"""Cost-based admission: a render's memory and work are estimated before it runs
and refused with 422 and the estimate beyond the per-render caps; renders share
the process's memory budget; the estimate and the time spent waiting for
admission are in the statistics and in Server-Timing; a small render is not
stuck behind a large one."""
import os
import subprocess
import threading
import time

import requests

from conftest import BEARING, SCREW, TIMEOUT, check_problem, healthy, post_raw, validate


def render(url, data, **params):
    return post_raw(url, "/v1/renders", data, params=params, headers={"Accept": "application/json"})


def test_estimate_and_queue_time_are_reported(url):
    r = render(url, SCREW.read_bytes(), width=160, height=120)
    assert r.status_code == 200, r.text[:300]
    stats = r.json()["statistics"]
    validate(stats, "Statistics")
    est = stats["estimate"]
    # 160 x 120 of a 10-face part: tens of MiB at most, a small fraction of a core-second, interactive.
    assert 1 < est["memory_mb"] < 100, est
    assert 0 < est["core_seconds"] < 0.5, est
    assert est["priority"] == "high"
    assert stats["timings_ms"]["queue"] >= 0
    assert "queue;dur=" in r.headers["Server-Timing"]


def test_estimate_grows_with_the_image(url):
    small = render(url, SCREW.read_bytes(), width=100, height=100).json()["statistics"]["estimate"]
    large = render(url, SCREW.read_bytes(), width=1000, height=1000).json()["statistics"]["estimate"]
    # 100x the pixels: the work is nearly all per pixel; the memory adds a fixed part (GL context, stacks).
    assert 5 < large["memory_mb"] / small["memory_mb"] < 100
    assert 50 < large["core_seconds"] / small["core_seconds"] < 101


def test_per_render_caps_refuse_with_the_estimate(own_server):
    s = own_server(args=["--max-render-mb", "100", "--max-render-cost", "1"])
    step = SCREW.read_bytes()
    assert render(s.url, step, width=320, height=240).status_code == 200
    body = check_problem(render(s.url, step, width=2000, height=2000), 422, "limit_exceeded")
    assert "estimated" in body["detail"] and "MiB" in body["detail"] and "100 MiB per render" in body["detail"]
    s2 = own_server(args=["--max-render-cost", "0.05"])
    body = check_problem(render(s2.url, step, width=1000, height=1000), 422, "limit_exceeded")
    assert "core-seconds" in body["detail"], body
    healthy(s2.url)


def test_memory_budget_bounds_the_renders_together(own_server):
    # Cache 64 MiB + the service's 320 MiB base: 200 MiB are left for renders.
    s = own_server(args=["--memory-budget-mb", "584", "--cache-mb", "64"])
    ready = requests.get(s.url + "/readyz", timeout=TIMEOUT).json()
    validate(ready, "Readiness")
    assert ready["renders"]["memory_capacity_mb"] == 200
    assert ready["renders"]["memory_used_mb"] == 0
    # One render estimated beyond all the renders' memory: refused at once, not queued for ever.
    body = check_problem(render(s.url, SCREW.read_bytes(), width=1400, height=1400), 422, "limit_exceeded")
    assert "200 MiB in all" in body["detail"], body
    assert render(s.url, SCREW.read_bytes(), width=320, height=240).status_code == 200
    m = requests.get(s.url + "/metrics", timeout=TIMEOUT).text
    assert "nurbsrt_render_memory_capacity_bytes 209715200\n" in m
    assert "nurbsrt_render_memory_reserved_bytes 0\n" in m


def test_budget_too_small_for_cache_and_base_refuses_to_start(tmp_path):
    p = subprocess.run([os.environ["NURBSRT_BIN"], "serve", "--port", "0", "--data-dir", str(tmp_path / "d"),
                        "--memory-budget-mb", "500", "--cache-mb", "256"],
                       capture_output=True, timeout=30)
    assert p.returncode != 0
    assert b"memory budget" in p.stderr and b"less than 64 MiB for renders" in p.stderr, p.stderr[-400:]


def test_small_render_is_not_stuck_behind_large_ones(own_server):
    """Two large renders take the whole memory budget left for renders and the
    cores; a small render meanwhile is admitted at once (it overtakes large
    work waiting for memory) and finishes before them. Ordering, not timing:
    the assertion is that it ends while both large ones are still running."""
    s = own_server(args=["--memory-budget-mb", "1600", "--cache-mb", "64", "--render-threads", "2"])
    bearing, screw = BEARING.read_bytes(), SCREW.read_bytes()
    for data in (bearing, screw):  # cache both scenes
        assert render(s.url, data, width=32, height=32).status_code == 200
    large_done = []

    def large():
        r = render(s.url, bearing, width=2200, height=2200)  # ~1.1 GiB estimated
        large_done.append((time.monotonic(), r.status_code, r.json()["statistics"]["timings_ms"]["queue"]))

    threads = [threading.Thread(target=large) for _ in range(2)]
    for t in threads:
        t.start()
    deadline = time.monotonic() + 60
    while requests.get(s.url + "/readyz", timeout=TIMEOUT).json()["renders"]["active"] < 1:
        assert time.monotonic() < deadline
        time.sleep(0.05)
    r = render(s.url, screw, width=160, height=120)
    small_done = time.monotonic()
    assert r.status_code == 200
    assert r.json()["statistics"]["estimate"]["priority"] == "high"
    for t in threads:
        t.join()
    assert [code for _, code, _ in large_done] == [200, 200]
    # The memory left for renders (1216 MiB) holds one large frame at a time: the second one waited.
    assert max(q for _, _, q in large_done) > 0
    assert small_done < min(t for t, _, _ in large_done), "the small render waited for a large one"
