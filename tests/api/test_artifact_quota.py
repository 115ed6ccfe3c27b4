"""The job artifacts of all kept jobs are bounded together (--max-artifacts-mb): a job whose estimated
artifacts do not fit next to those already written is refused with 507 at submission, and an output whose
artifact would pass the quota when written fails with limit_exceeded (its file removed), so the disk never
holds more than the quota (and one artifact per runner checking at the same time)."""
import json
import time

import requests

from conftest import SCREW, TIMEOUT, check_problem, healthy

MIB = 1 << 20


def submit(base, spec):
    return requests.post(base + "/v1/jobs", timeout=TIMEOUT,
                         files=[("file", ("s.step", SCREW.read_bytes(), "application/octet-stream")),
                                ("job", (None, json.dumps(spec), "application/json"))])


def wait_done(base, job_id, timeout=120):
    deadline = time.monotonic() + timeout
    while (job := requests.get(f"{base}/v1/jobs/{job_id}", timeout=TIMEOUT).json())["state"] not in (
            "succeeded", "failed"):
        assert time.monotonic() < deadline, json.dumps(job)[:400]
        time.sleep(0.1)
    return job


def test_a_job_beyond_the_quota_is_refused_with_507(own_server):
    s = own_server(args=["--max-artifacts-mb", "2"])
    # 1000x1000 PNG: up to 4 MB (uncompressed RGBA) against a quota of 2 MiB.
    r = submit(s.url, {"outputs": [{"file": 0, "type": "render", "options": {"width": 1000, "height": 1000}}]})
    p = check_problem(r, 507, "limit_exceeded")
    assert "artifact quota of 2 MiB" in p["detail"], p["detail"]
    # Within it: accepted and made.
    r = submit(s.url, {"outputs": [{"file": 0, "type": "render", "options": {"width": 200, "height": 150}}]})
    assert r.status_code == 202, r.text[:300]
    assert wait_done(s.url, r.json()["id"])["state"] == "succeeded"


def test_artifacts_written_never_pass_the_quota(own_server):
    """One runner, held by a render while eight jobs of four STEP conversions are accepted (each estimated
    at 4x its 88 KB input, so each fits the empty quota alone); their artifacts (~87 KB each) do not all fit:
    the outputs beyond the quota fail at write time, and the next job is refused at submission."""
    quota_mb = 1.9
    s = own_server(args=["--max-artifacts-mb", str(quota_mb), "--job-runners", "1", "--workers", "1",
                         "--render-threads", "1"])
    hold = submit(s.url, {"outputs": [{"file": 0, "type": "render", "options": {
        "width": 300, "height": 300, "antialias": 64, "shadows": True, "edges": True}}]})
    assert hold.status_code == 202, hold.text[:300]
    conversions = {"outputs": [{"file": 0, "type": "conversion", "format": "step"}] * 4}
    ids = [hold.json()["id"]]
    for _ in range(8):
        r = submit(s.url, conversions)
        if r.status_code == 202:
            ids.append(r.json()["id"])
        else:
            check_problem(r, 507, "limit_exceeded")
    assert len(ids) >= 5, f"only {len(ids) - 1} of 8 jobs were accepted: the holding render ended too soon"
    jobs = [wait_done(s.url, i) for i in ids]
    outputs = [o for j in jobs for o in j["outputs"]]
    written = sum(o["artifact"]["bytes"] for o in outputs if o["state"] == "succeeded")
    refused = [o for o in outputs if o["state"] == "failed"]
    assert written <= quota_mb * MIB, (written, quota_mb * MIB)
    assert refused, f"every output was written ({written} bytes): the test lost its point"
    for o in refused:
        assert o["error"]["code"] == "limit_exceeded" and "artifact quota" in o["error"]["message"], o["error"]
    # On disk too: the artifacts of the refused outputs are gone, no partial file is left.
    on_disk = [p for i in ids for p in (s.data_dir / "jobs" / i).iterdir() if not p.name.startswith("input")]
    assert not [p.name for p in on_disk if p.name.startswith("partial-")]
    assert sum(p.stat().st_size for p in on_disk) == written
    check_problem(submit(s.url, conversions), 507, "limit_exceeded")
    healthy(s.url)
