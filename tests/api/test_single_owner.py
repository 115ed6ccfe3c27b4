"""One owner per data directory and per port. With the SQLite job store a data
directory belongs to one `serve`: a second one on it would requeue the first
one's running jobs at its start-up recovery and sweep its scratch files, so it
stops at once, naming the directory and the holder's pid. A busy port is never
shared (cpp-httplib bound with SO_REUSEPORT, and a second service silently
took half the connections)."""
import os
import subprocess
import tempfile
from urllib.parse import urlparse

import requests

from conftest import PG_ADMIN, TIMEOUT, healthy, pg_store_for, sqlite_only


def serve(args, data_dir):
    store = ["--job-store", pg_store_for(data_dir)] if PG_ADMIN else []
    return subprocess.run([os.environ["NURBSRT_BIN"], "serve", "--data-dir", str(data_dir), *store, *args],
                          capture_output=True, text=True, timeout=30, stdin=subprocess.DEVNULL)


@sqlite_only
def test_second_instance_on_a_data_dir_exits_naming_the_holder(own_server, tmp_path):
    first = own_server(data_dir=tmp_path / "data")
    second = serve(["--port", "0"], tmp_path / "data")
    assert second.returncode == 1, second.stderr
    assert str(tmp_path / "data") in second.stderr and f"pid {first.proc.pid}" in second.stderr, second.stderr
    assert "in use by another nurbsrt serve" in second.stderr
    healthy(first.url)  # the holder goes on
    # Once the holder has stopped (here: killed, which releases the lock too) the directory is free.
    first.proc.kill()
    first.proc.wait(timeout=10)
    again = own_server(data_dir=tmp_path / "data")
    healthy(again.url)


def test_busy_port_exits_saying_so(own_server):
    first = own_server()
    port = urlparse(first.url).port
    with tempfile.TemporaryDirectory() as other:
        second = serve(["--host", "127.0.0.1", "--port", str(port)], os.path.join(other, "data"))
    assert second.returncode == 1, second.stderr
    assert f"127.0.0.1:{port}" in second.stderr and "the port is in use" in second.stderr, second.stderr
    # Every request still reaches the first service.
    for _ in range(20):
        assert requests.get(first.url + "/healthz", timeout=TIMEOUT).status_code == 200
