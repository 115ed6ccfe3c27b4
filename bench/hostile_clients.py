"""Before/after figures of the hostile-client defects, from one running service.

Usage: /usr/bin/python3 bench/hostile_clients.py path/to/nurbsrt PORT
Starts `nurbsrt serve` (4 MiB uploads, 1 worker) on 127.0.0.1:PORT with a temporary data dir and prints:
a gzip bomb (254 KiB -> 256 MiB: status, time, peak RSS), a lying Content-Length, 30 slowloris
connections against /healthz, keep-alive latency, the listen backlog (ss), the 414 body status and
PUT on a known route. The assertions live in tests/api/test_hostile.py; this prints the numbers."""
import os, socket, subprocess, sys, tempfile, time, zlib, threading, statistics, requests
bin_ = sys.argv[1]; port = int(sys.argv[2])
d = tempfile.mkdtemp()
p = subprocess.Popen([bin_, "serve", "--port", str(port), "--data-dir", d, "--max-upload-mb", "4", "--workers", "1", "--max-queue", "1"], stderr=subprocess.DEVNULL)
time.sleep(1.5)
url = f"http://127.0.0.1:{port}"
def hwm():
    for l in open(f"/proc/{p.pid}/status"):
        if l.startswith("VmHWM"): return int(l.split()[1]) // 1024
c = zlib.compressobj(9, zlib.DEFLATED, 31); blk = b" " * (1 << 20)
bomb = c.compress(b"ISO-10303-21;\n") + b"".join(c.compress(blk) for _ in range(256)) + c.flush()
h0 = hwm(); t = time.monotonic()
r = requests.post(url + "/v1/renders", data=bomb, headers={"Content-Encoding": "gzip", "Content-Type": "application/octet-stream"}, timeout=300)
print(f"D1 gzip bomb ({len(bomb)//1024} KiB -> 256 MiB): {r.status_code} in {time.monotonic()-t:.2f} s, peak RSS {h0} -> {hwm()} MiB")
s = socket.create_connection(("127.0.0.1", port)); t = time.monotonic()
s.sendall(b"POST /v1/renders HTTP/1.1\r\nHost: x\r\nContent-Length: 100000000000\r\n\r\n"); s.settimeout(60)
try: st = s.recv(100)[:12]
except Exception as e: st = repr(e)
print(f"D2 lying Content-Length over the limit: {st} after {time.monotonic()-t:.2f} s")
stop = threading.Event()
def slow():
    try:
        with socket.create_connection(("127.0.0.1", port)) as k:
            for b in b"GET /healthz HTTP/1.1\r\nX-A: " + b"a" * 100:
                if stop.is_set(): return
                k.sendall(bytes([b])); stop.wait(0.5)
    except OSError: pass
ths = [threading.Thread(target=slow) for _ in range(30)]
[x.start() for x in ths]; time.sleep(1)
lat = []
for _ in range(10):
    t = time.monotonic()
    try: requests.get(url + "/healthz", timeout=5); lat.append(time.monotonic() - t)
    except Exception: lat.append(float("inf"))
stop.set()
print(f"D2 slowloris 30 conns: /healthz median {statistics.median(lat)*1000:.1f} ms, max {max(lat)*1000:.1f} ms ({sum(x==float('inf') for x in lat)} of 10 timed out at 5 s)")
[x.join() for x in ths]
with requests.Session() as sess:
    ts = []
    for _ in range(10):
        t = time.monotonic(); sess.get(url + "/healthz"); ts.append(time.monotonic() - t)
print(f"D11 keep-alive: median of requests 2..10 {statistics.median(ts[1:])*1000:.1f} ms")
out = subprocess.run(["ss", "-ltnH", f"sport = :{port}"], capture_output=True, text=True).stdout.split()
print(f"D7 listen backlog: {out[2]}")
r = requests.get(url + "/v1/jobs?x=" + "a" * 9000)
print(f"D10 414 body status: {r.json().get('status')}")
r = requests.put(url + "/v1/renders")
print(f"D12 PUT /v1/renders: {r.status_code}")
p.terminate(); p.wait()
