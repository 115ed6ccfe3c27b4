"""16 concurrent renders against 2 workers + 2 queue slots: every request ends
in success or a proper 503/429 with Retry-After; none hangs."""
import concurrent.futures
import time

import requests

from conftest import BEARING, TIMEOUT, check_problem, healthy, post_raw


def test_sixteen_concurrent_renders(url):
    data = BEARING.read_bytes()
    post_raw(url, "/v1/renders", data, params={"width": 32, "height": 32})  # warm the cache

    def one(i):
        return post_raw(url, "/v1/renders", data, params={"width": 320, "height": 240, "method": "martin"})

    t0 = time.monotonic()
    with concurrent.futures.ThreadPoolExecutor(max_workers=16) as pool:
        results = list(pool.map(one, range(16), timeout=TIMEOUT))
    assert time.monotonic() - t0 < TIMEOUT
    statuses = [r.status_code for r in results]
    assert all(s in (200, 429, 503) for s in statuses), statuses
    assert statuses.count(200) >= 2, statuses
    for r in results:
        if r.status_code != 200:
            check_problem(r, r.status_code, "overloaded")
            assert int(r.headers["Retry-After"]) >= 1
    healthy(url)
