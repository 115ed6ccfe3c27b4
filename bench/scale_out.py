"""Driver of bench/scale_out.sh (see there)."""
import json
import os
import pathlib
import signal
import statistics
import subprocess
import sys
import tempfile
import time
from datetime import datetime

import requests

ADMIN = os.environ["NURBSRT_TEST_PG_ADMIN"]
SCREW = pathlib.Path("/usr/share/opencascade/data/step/screw.step").read_bytes()
# force: the same file and spec every time, each job made anew (no artifact reuse).
SPEC = {"outputs": [{"file": 0, "type": "render", "options": {"width": 320, "height": 240}},
                    {"file": 0, "type": "conversion", "format": "iges"}], "force": True}


def start(n, store, tmp):
    procs, urls = [], []
    for i in range(n):
        port_file = tmp / f"port{i}"
        args = [os.environ["NURBSRT_BIN"], "serve", "--port", "0", "--port-file", str(port_file),
                "--data-dir", str(tmp / "data"), "--workers", "1", "--job-runners", "1", "--render-threads", "1"]
        if store:
            args += ["--job-store", store]
        procs.append(subprocess.Popen(args, stderr=subprocess.DEVNULL))
        while not (port_file.exists() and port_file.read_text().strip()):
            time.sleep(0.05)
        urls.append(f"http://127.0.0.1:{port_file.read_text().strip()}")
    return procs, urls


def submit(url):
    r = requests.post(url + "/v1/jobs", files=[("file", ("s.step", SCREW, "application/octet-stream")),
                                               ("job", (None, json.dumps(SPEC), "application/json"))], timeout=60)
    assert r.status_code == 202, r.text
    return r.json()["id"]


def wait(url, job_id):
    while True:
        j = requests.get(f"{url}/v1/jobs/{job_id}", timeout=60).json()
        if j["state"] in ("succeeded", "failed"):
            assert j["state"] == "succeeded", j
            return j
        time.sleep(0.05)


def ts(text):
    return datetime.fromisoformat(text.replace("Z", "+00:00")).timestamp()


def run(label, n, store, jobs):
    tmp = pathlib.Path(tempfile.mkdtemp(prefix="nurbsrt-bench-"))
    procs, urls = start(n, store, tmp)
    try:
        # Queue-to-start latency: one job at a time on an idle service.
        lat = []
        for i in range(6):
            j = wait(urls[i % n], submit(urls[i % n]))
            lat.append((ts(j["started_at"]) - ts(j["created_at"])) * 1000)
        # Throughput: the whole batch at once, spread over the instances.
        t0 = time.monotonic()
        ids = [(urls[i % n], submit(urls[i % n])) for i in range(jobs)]
        for url, job_id in ids:
            wait(url, job_id)
        minutes = (time.monotonic() - t0) / 60
        print(f"| {label} | {n} | {jobs / minutes:.1f} | {statistics.median(lat):.0f} |", flush=True)
    finally:
        for p in procs:
            p.send_signal(signal.SIGTERM)
        for p in procs:
            p.wait(timeout=60)
        subprocess.run(["rm", "-rf", str(tmp)])


def main():
    jobs = int(sys.argv[1])
    print(f"{jobs} jobs per batch, each a 320x240 render and an IGES conversion of screw.step; "
          f"{os.cpu_count()} cores")
    print("| store | instances | jobs/min | median queue-to-start ms |\n|---|---|---|---|")
    run("SQLite", 1, None, jobs)
    for n in (1, 2, 3):
        db = f"bench{n}"
        subprocess.run(["psql", "-q", ADMIN, "-c", f"CREATE DATABASE {db}"], check=True, capture_output=True)
        run("PostgreSQL", n, ADMIN.rsplit("/", 1)[0] + "/" + db, jobs)


if __name__ == "__main__":
    main()
