#!/usr/bin/env bash
# Brings up docker/compose.scale.yaml (PostgreSQL, 3 nurbsrt instances, HAProxy)
# and checks it as a user of the balancer would: every instance answers behind
# it, jobs sent through it succeed, one instance SIGKILLed while it runs outputs
# loses no job (its leases expire and the others finish its work, each output
# completed once, counted in the database), every artifact downloads whole
# through the balancer. Then takes it down again (KEEP=1 leaves it running).
# Needs the images (compose builds them; with no registry the Debian base image
# is made locally, see the containers section of the README).
# Usage: docker/verify-compose-scale.sh     (from the repository root)
#   COMPOSE="docker compose" ENGINE=docker docker/verify-compose-scale.sh
set -euo pipefail
cd "$(dirname "$0")/.."
COMPOSE=${COMPOSE:-podman-compose}
ENGINE=${ENGINE:-podman}
PROJECT=${PROJECT:-nurbsrtscale}
export NURBSRT_BALANCER_PORT=${NURBSRT_BALANCER_PORT:-18090}
compose() { $COMPOSE -p "$PROJECT" -f docker/compose.scale.yaml "$@"; }

down() {
  if [ "${KEEP:-0}" != 1 ]; then compose down -v > /dev/null 2>&1 || true; fi
}
trap down EXIT
t0=$(date +%s)
compose up -d > /tmp/verify-compose-scale.log 2>&1 || { cat /tmp/verify-compose-scale.log; exit 1; }
echo "verify-compose-scale: up in $(( $(date +%s) - t0 )) s"

# The containers of this project by service, as "service name id" lines.
containers() {
  for service in postgres nurbsrt balancer; do
    $ENGINE ps --filter "label=com.docker.compose.project=$PROJECT" \
      --filter "label=com.docker.compose.service=$service" --format "$service {{.Names}} {{.ID}}"
  done
}
PG=$(containers | awk '$1 == "postgres" {print $2}')
export PG ENGINE PROJECT
CONTAINERS=$(containers)
export CONTAINERS
/usr/bin/python3 - <<'EOF'
import json, os, pathlib, subprocess, sys, time
import requests
sys.path.insert(0, "tests/api")
from test_jobs import check_artifact  # noqa: E402

BASE = f"http://127.0.0.1:{os.environ['NURBSRT_BALANCER_PORT']}"
ENGINE, PG = os.environ["ENGINE"], os.environ["PG"]
OCCT = pathlib.Path("/usr/share/opencascade/data")
FILES = [OCCT / "step" / "screw.step", OCCT / "step" / "linkrods.step", OCCT / "iges" / "bearing.iges"]
JOBS = 12


def sql(query):
    out = subprocess.run([ENGINE, "exec", PG, "psql", "-U", "nurbsrt", "-d", "nurbsrt", "-qtA", "-F", "|",
                          "-c", query], capture_output=True, text=True, check=True).stdout
    return [line.split("|") for line in out.splitlines() if line]


def wait_until(pred, timeout, what):
    deadline = time.monotonic() + timeout
    while True:
        try:
            if pred():
                return
        except requests.RequestException:
            pass  # the balancer may have no instance for a moment
        assert time.monotonic() < deadline, what
        time.sleep(0.5)


def instances_behind_balancer():
    seen = set()
    for _ in range(60):
        text = requests.get(BASE + "/metrics", timeout=10).text
        line = next(l for l in text.splitlines() if l.startswith("nurbsrt_instance_info{"))
        seen.add(line.split('instance="')[1].split('"')[0])
    return seen


wait_until(lambda: len(instances_behind_balancer()) == 3, 240, "three instances never answered behind the balancer")
t_ready = time.monotonic()
print(f"verify-compose-scale: instances behind the balancer: {sorted(instances_behind_balancer())}")

jobs = []
for n in range(JOBS):
    src = FILES[n % len(FILES)]
    spec = {"outputs": [{"file": 0, "type": "render", "options": {"width": 480 + 32 * (n % 4), "height": 360}},
                        {"file": 0, "type": "conversion", "format": "iges" if src.suffix == ".step" else "step"}]}
    r = requests.post(BASE + "/v1/jobs", timeout=60,
                      files=[("file", (src.name, src.read_bytes(), "application/octet-stream")),
                             ("job", (None, json.dumps(spec), "application/json"))])
    assert r.status_code == 202, r.text[:300]
    jobs.append(r.json()["id"])
ids = ",".join(f"'{j}'" for j in jobs)

# SIGKILL the instance that runs an output, as a lost machine would.
wait_until(lambda: sql(f"SELECT 1 FROM job_outputs WHERE job_id IN ({ids}) AND state = 'running'"), 120,
           "no output ever ran")
owner = sql(f"SELECT lease_owner FROM job_outputs WHERE job_id IN ({ids}) AND state = 'running' LIMIT 1")[0][0]
container = next(line.split()[1] for line in os.environ["CONTAINERS"].splitlines()
                 if line.split()[0] == "nurbsrt" and owner.startswith(line.split()[2][:12]))
held = sql(f"SELECT job_id, idx FROM job_outputs WHERE lease_owner = '{owner}' AND state = 'running'")
subprocess.run([ENGINE, "kill", "--signal", "KILL", container], check=True, capture_output=True)
t_kill = time.monotonic()
print(f"verify-compose-scale: SIGKILLed {container} (instance {owner}) holding {len(held)} running output(s)")

for job_id in jobs:
    def done():
        job = requests.get(f"{BASE}/v1/jobs/{job_id}", timeout=30).json()
        return job["state"] in ("succeeded", "failed", "canceled")
    wait_until(done, 600, f"job {job_id} never ended")
total_s = time.monotonic() - t_kill
artifacts = 0
for job_id in jobs:
    job = requests.get(f"{BASE}/v1/jobs/{job_id}", timeout=30).json()
    assert job["state"] == "succeeded", json.dumps(job)[:800]
    for out in job["outputs"]:
        check_artifact(BASE, out)
        artifacts += 1
(outputs, once, most, rerun), = sql(f"SELECT COUNT(*), SUM((completions = 1)::int), MAX(completions), "
                                    f"SUM((attempts > 1)::int) FROM job_outputs WHERE job_id IN ({ids})")
assert int(outputs) == 2 * JOBS == int(once) and int(most) == 1, (outputs, once, most)
taken = sql(f"SELECT COUNT(*) FROM job_outputs WHERE job_id IN ({ids}) AND attempts > 1 AND lease_owner <> '{owner}'")
assert held and int(rerun) >= len(held), (held, rerun)
by_owner = dict(sql(f"SELECT lease_owner, COUNT(*) FROM job_outputs WHERE job_id IN ({ids}) GROUP BY lease_owner"))
print(f"verify-compose-scale: {JOBS} jobs ({2 * JOBS} outputs) through the balancer all succeeded, {artifacts} "
      f"artifacts whole; {rerun} output(s) re-run after the kill ({taken[0][0]} by another instance), each output "
      f"completed once; all done {total_s:.0f} s after the kill (lease 30 s); completed by instance: {by_owner}")
EOF
echo "verify-compose-scale: passed in $(( $(date +%s) - t0 )) s"
