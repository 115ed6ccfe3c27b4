"""A crashing or hanging import child fails only its own request (test hook
NURBSRT_IMPORT_WORKER_FAULT, read only by worker processes)."""
import time

from conftest import SCREW, check_problem, healthy, post_raw


def test_crashing_import_fails_only_its_request(own_server):
    s = own_server(env={"NURBSRT_IMPORT_WORKER_FAULT": "crash"})
    check_problem(post_raw(s.url, "/v1/renders", SCREW.read_bytes(), params={"width": 32, "height": 32}),
                  422, "import_crashed")
    check_problem(post_raw(s.url, "/v1/conversions", SCREW.read_bytes(), params={"format": "iges"}),
                  422, "import_crashed")
    healthy(s.url)
    assert s.proc.poll() is None
    # ...and the next request is served normally by the same server (errors need no worker).
    check_problem(post_raw(s.url, "/v1/renders", b"garbage"), 415)


def test_hanging_import_times_out(own_server):
    s = own_server(args=["--import-timeout", "2"], env={"NURBSRT_IMPORT_WORKER_FAULT": "hang"})
    t0 = time.monotonic()
    check_problem(post_raw(s.url, "/v1/renders", SCREW.read_bytes(), params={"width": 32, "height": 32}),
                  504, "import_timeout")
    assert time.monotonic() - t0 < 20
    healthy(s.url)
    m = __import__("requests").get(s.url + "/metrics", timeout=30).text
    assert 'nurbsrt_import_failures_total{code="import_timeout"} 1' in m


def test_render_over_its_time_limit_is_504(own_server):
    s = own_server(args=["--render-timeout", "0.001"])
    check_problem(post_raw(s.url, "/v1/renders", SCREW.read_bytes(), params={"width": 400, "height": 300}),
                  504, "render_timeout")
    healthy(s.url)
