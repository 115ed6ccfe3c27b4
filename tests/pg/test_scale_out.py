"""Three instances on one PostgreSQL job queue and one shared data directory.

A job is canceled through another instance than the one running it; then 30 jobs
(renders and conversions of four files) are spread over the instances, one instance
is SIGKILLed while it runs outputs, and: every job ends succeeded with its artifacts
present and decodable from any instance, no output was completed twice (counted in
the database), the jobs submitted to the dead instance were served by the others,
and GET answers the same on every instance. Then one job of nine files x (render,
STL, glb): its files are claimed by different instances, one instance is SIGKILLed
holding a file, and every output ends succeeded exactly once with one artifact.
Prints the counts and times."""
import json
import os
import pathlib
import signal
import subprocess
import sys
import tempfile
import time

import requests

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1] / "api"))
from test_jobs import accepted, check_artifact, get_job, submit  # noqa: E402

PG_URL = os.environ["NURBSRT_TEST_PG_URL"]
OCCT = pathlib.Path("/usr/share/opencascade/data")
FILES = [OCCT / "step" / "screw.step", OCCT / "step" / "linkrods.step", OCCT / "iges" / "bearing.iges",
         OCCT / "iges" / "hammer.iges"]
LEASE_S = 3
JOBS = 30


def sql(query):
    out = subprocess.run(["psql", "-qtA", "-F", "|", PG_URL, "-c", query], capture_output=True, text=True,
                         check=True).stdout
    return [line.split("|") for line in out.splitlines() if line]


class Instance:
    def __init__(self, name, data_dir, tmp):
        self.name = name
        port_file = tmp / f"{name}.port"
        self.log_path = tmp / f"{name}.log"
        self.log = open(self.log_path, "wb")
        self.proc = subprocess.Popen(
            [os.environ["NURBSRT_BIN"], "serve", "--port", "0", "--port-file", str(port_file),
             "--data-dir", str(data_dir), "--job-store", PG_URL, "--lease-seconds", str(LEASE_S),
             "--instance-id", name, "--workers", "1", "--job-runners", "1", "--render-threads", "1"],
            stderr=self.log)
        for _ in range(200):
            if port_file.exists() and port_file.read_text().strip():
                break
            assert self.proc.poll() is None, self.log_path.read_text()[-2000:]
            time.sleep(0.1)
        self.url = f"http://127.0.0.1:{port_file.read_text().strip()}"

    def stop(self):
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGTERM)
            try:
                self.proc.wait(timeout=30)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()
        self.log.close()


def spec_for(n):
    """A render and a conversion of one file; sizes vary so outputs end at different times."""
    src = FILES[n % len(FILES)]
    target = "iges" if src.suffix == ".step" else "step"
    size = 160 + 40 * (n % 5)
    # force: specs repeat every 20 jobs; each is made anew, not served from an earlier job's artifacts.
    return src, {"outputs": [{"file": 0, "type": "render", "options": {"width": size, "height": size}},
                             {"file": 0, "type": "conversion", "format": target}], "force": True}


def wait_until(pred, timeout, what):
    deadline = time.monotonic() + timeout
    while not pred():
        assert time.monotonic() < deadline, what
        time.sleep(0.05)


def cancel_across_instances(insts, data_dir):
    """DELETE through an instance that is not the one running the job stops it there."""
    src = FILES[2]
    job = accepted(submit(insts[0].url, [(src.name, src.read_bytes())],
                          {"outputs": [{"file": 0, "type": "render", "options": {"width": 2000, "height": 2000}}]}))
    wait_until(lambda: sql(f"SELECT lease_owner FROM job_outputs WHERE job_id = '{job['id']}' AND state = 'running'"),
               60, "the long render never started")
    owner = sql(f"SELECT lease_owner FROM job_outputs WHERE job_id = '{job['id']}'")[0][0]
    other = next(i for i in insts if i.name != owner)
    t0 = time.monotonic()
    r = requests.delete(f"{other.url}/v1/jobs/{job['id']}", timeout=30)
    assert r.status_code in (202, 204), r.text[:300]
    for inst in insts:  # gone everywhere once the owner stopped the render and removed it
        wait_until(lambda: requests.get(f"{inst.url}/v1/jobs/{job['id']}", timeout=30).status_code == 404, 30,
                   f"the canceled job is still visible on {inst.name}")
    wait_until(lambda: not (data_dir / "jobs" / job["id"]).exists(), 10, "the canceled job's files remain")
    owner_inst = next(i for i in insts if i.name == owner)
    metrics = requests.get(owner_inst.url + "/metrics", timeout=30).text
    assert 'nurbsrt_jobs_finished_total{result="canceled"} 1' in metrics
    return owner, other.name, time.monotonic() - t0


def test_three_instances_survive_losing_one():
    tmp = pathlib.Path(tempfile.mkdtemp(prefix="nurbsrt-scale-"))
    data_dir = tmp / "data"
    insts = [Instance(name, data_dir, tmp) for name in ("inst-a", "inst-b", "inst-c")]
    victim = insts[2]
    try:
        owner, via, cancel_s = cancel_across_instances(insts, data_dir)
        print(f"\nscale_out: cancel: job running on {owner}, DELETE via {via}, gone everywhere after {cancel_s:.1f} s")

        t_start = time.monotonic()
        jobs = {}  # id -> (instance it was submitted to, spec)
        for n in range(JOBS):
            src, spec = spec_for(n)
            inst = insts[n % 3]
            jobs[accepted(submit(inst.url, [(src.name, src.read_bytes())], spec))["id"]] = (inst.name, spec)
        # Kill the victim while it holds a running output.
        wait_until(lambda: sql("SELECT 1 FROM job_outputs WHERE lease_owner = 'inst-c' AND state = 'running' "
                               "AND lease_token <> ''"), 120, "inst-c never ran an output")
        held = sql("SELECT job_id, idx FROM job_outputs WHERE lease_owner = 'inst-c' AND lease_token <> '' "
                   "AND state IN ('queued', 'running')")
        victim.proc.kill()
        t_kill = time.monotonic()
        # When its leases run out, in the database's clock, seen from now.
        (expiry_s,), = sql("SELECT (MAX(lease_expires_ms) - (extract(epoch FROM clock_timestamp()) * 1000)::bigint) "
                           "/ 1000.0 FROM job_outputs WHERE lease_owner = 'inst-c' AND lease_token <> ''")
        victim.proc.wait(timeout=10)
        assert held, "inst-c held nothing when killed"
        survivors = insts[:2]

        # Its outputs are claimed again by the others once the lease expired.
        def resumed():
            return all(sql(f"SELECT 1 FROM job_outputs WHERE job_id = '{j}' AND idx = {i} AND "
                           f"(lease_owner <> 'inst-c' OR state IN ('succeeded', 'failed'))") for j, i in held)
        wait_until(resumed, 60, "the dead instance's outputs were never taken over")
        resume_s = time.monotonic() - t_kill

        finished = {}
        for n, job_id in enumerate(jobs):
            via_inst = survivors[n % 2]
            deadline = time.monotonic() + 400
            while True:
                job = get_job(via_inst.url, job_id)
                if job["state"] in ("succeeded", "failed", "canceled"):
                    break
                assert time.monotonic() < deadline, json.dumps(job)[:600]
                time.sleep(0.2)
            finished[job_id] = job
        total_s = time.monotonic() - t_start
        for job_id, job in finished.items():
            assert job["state"] == "succeeded", json.dumps(job)[:800]
            for out in job["outputs"]:
                check_artifact(survivors[1].url, out)
            # The same answer from either survivor.
            assert get_job(survivors[0].url, job_id) == get_job(survivors[1].url, job_id)

        ids = ",".join(f"'{j}'" for j in jobs)
        (outputs, completed_once, max_completions, rerun), = sql(
            f"SELECT COUNT(*), SUM((completions = 1)::int), MAX(completions), SUM((attempts > 1)::int) "
            f"FROM job_outputs WHERE job_id IN ({ids})")
        assert int(outputs) == 2 * JOBS and int(completed_once) == 2 * JOBS and int(max_completions) == 1
        on_victim = [j for j, (name, _) in jobs.items() if name == "inst-c"]
        by_owner = dict(sql(f"SELECT lease_owner, COUNT(*) FROM job_outputs WHERE job_id IN ({ids}) "
                            f"GROUP BY lease_owner"))
        assert int(rerun) >= 1
        assert sum(1 for j in on_victim if finished[j]["state"] == "succeeded") == len(on_victim)
        print(f"scale_out: {JOBS} jobs ({2 * JOBS} outputs) on 3 instances, inst-c SIGKILLed holding "
              f"{len(held)} output(s); {rerun} output(s) re-run after the kill; every output completed exactly once; "
              f"lease {LEASE_S} s: its lease expired {max(float(expiry_s or 0), 0):.1f} s after the kill and its work "
              f"was taken over {resume_s:.1f} s after the kill (by the first runner to come free); "
              f"{len(on_victim)} jobs submitted to inst-c all succeeded; outputs completed by instance: {by_owner}; "
              f"all jobs done in {total_s:.1f} s")
    finally:
        for inst in insts:
            inst.stop()
        for inst in insts:
            if inst is not victim and inst.proc.returncode not in (0, None):
                print(inst.log_path.read_text()[-3000:])
        subprocess.run(["rm", "-rf", str(tmp)])


def test_one_job_of_nine_files_spread_over_three_instances_survives_losing_one():
    """One job of 9 files x (render + STL + glb): its files are claimed by different instances (a claim takes
    one file's outputs, which one read serves); one instance is SIGKILLed while it holds a file; every output
    ends succeeded exactly once (completions counted in the database), with one artifact each on disk."""
    from test_conversions import parse_glb, parse_stl
    tmp = pathlib.Path(tempfile.mkdtemp(prefix="nurbsrt-scale-files-"))
    data_dir = tmp / "data"
    insts = [Instance(name, data_dir, tmp) for name in ("inst-d", "inst-e", "inst-f")]
    victim = insts[2]
    try:
        # Nine distinct files (the same small part, each with its own trailing bytes: nine hashes, nine reads).
        screw = FILES[0].read_bytes()
        files = [(f"part{k}.step", screw + b"\n" * (k + 1)) for k in range(9)]
        spec = {"outputs": [o for k in range(9) for o in (
            {"file": k, "type": "render", "options": {"width": 160, "height": 120}},
            {"file": k, "type": "conversion", "format": "stl"},
            {"file": k, "type": "conversion", "format": "glb"})]}
        job_id = accepted(submit(insts[0].url, files, spec))["id"]
        wait_until(lambda: sql(f"SELECT 1 FROM job_outputs WHERE job_id = '{job_id}' AND lease_owner = 'inst-f' "
                               "AND lease_token <> '' AND state IN ('queued', 'running')"),
                   120, "inst-f never took a file of the job")
        held = sql(f"SELECT idx, file FROM job_outputs WHERE job_id = '{job_id}' AND lease_owner = 'inst-f' "
                   "AND lease_token <> '' AND state IN ('queued', 'running')")
        victim.proc.kill()
        victim.proc.wait(timeout=10)
        assert held and len({f for _, f in held}) == 1, held  # one claim: one file's outputs
        held_file = int(held[0][1])

        survivors = insts[:2]
        deadline = time.monotonic() + 300
        while (job := get_job(survivors[1].url, job_id))["state"] not in ("succeeded", "failed"):
            assert time.monotonic() < deadline, json.dumps(job)[:600]
            time.sleep(0.2)
        assert job["state"] == "succeeded", json.dumps(job)[:1000]
        assert get_job(survivors[0].url, job_id) == job
        outs = job["outputs"]
        assert len(outs) == 27 and all(o["state"] == "succeeded" for o in outs)
        for o in outs:
            data = requests.get(survivors[0].url + o["artifact"]["url"], timeout=60).content
            assert len(data) == o["artifact"]["bytes"] > 0
            if o["type"] == "render":
                check_artifact(survivors[0].url, o)
            elif o["format"] == "stl":
                assert len(parse_stl(data)) > 100
            else:
                assert parse_glb(data)[0]["meshes"]
        # One artifact per output on disk (the killed run's partial files aside: the age sweep removes them).
        names = sorted(p.name for p in (data_dir / "jobs" / job_id).iterdir()
                       if not p.name.startswith(("input-", "partial-")))
        assert names == sorted(o["artifact"]["name"] for o in outs), names
        (count, once, most, rerun, owners), = sql(
            f"SELECT COUNT(*), SUM((completions = 1)::int), MAX(completions), SUM((attempts > 1)::int), "
            f"COUNT(DISTINCT lease_owner) FROM job_outputs WHERE job_id = '{job_id}'")
        assert (int(count), int(once), int(most)) == (27, 27, 1)
        assert int(rerun) >= len(held)  # the killed instance's file ran again elsewhere
        assert int(owners) >= 2  # the job's files spread over the instances
        # Each file's outputs came from one read; the killed one's from two at most (what it finished, then
        # the rest after the takeover).
        by_file = {}
        for o in outs:
            by_file.setdefault(o["file"], set()).add((o.get("statistics") or o["report"])["read"]["id"])
        assert all(len(ids) == 1 for f, ids in by_file.items() if f != held_file), by_file
        # The job's events, appended by all three instances (the killed one included), read from each survivor:
        # one sequence 1..n, each output's end and artifact once, the terminal event last.
        streams = [requests.get(f"{inst.url}/v1/jobs/{job_id}/events", timeout=60).text for inst in survivors]
        assert streams[0] == streams[1]
        events = [dict(line.split(": ", 1) for line in block.split("\n"))
                  for block in streams[0].split("\n\n") if block]
        assert [int(e["id"]) for e in events] == list(range(1, len(events) + 1))
        ends = [json.loads(e["data"])["output"] for e in events
                if e["event"] == "output" and json.loads(e["data"])["state"] == "succeeded"]
        arts = [json.loads(e["data"])["output"] for e in events if e["event"] == "artifact"]
        assert sorted(ends) == sorted(arts) == list(range(27))
        assert events[-1]["event"] == "state" and json.loads(events[-1]["data"])["state"] == "succeeded"
        assert len(by_file[held_file]) in (1, 2) and job["statistics"]["reads"] == 8 + len(by_file[held_file])
        print(f"\nscale_out: one job of 9 files x 3 outputs on 3 instances, inst-f SIGKILLed holding file "
              f"{held_file} ({len(held)} outputs); {rerun} output(s) re-run; every output completed exactly once; "
              f"outputs completed by {owners} instance(s) in all")
    finally:
        for inst in insts:
            inst.stop()
        subprocess.run(["rm", "-rf", str(tmp)])
