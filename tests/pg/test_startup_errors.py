"""A bad configuration of the PostgreSQL job store stops `nurbsrt serve` at start-up with a
clear message and a non-zero exit: an unreachable server, a wrong password (never echoed),
a schema newer than the binary, a job directory that cannot be written."""
import os
import socket
import subprocess

PG_URL = os.environ["NURBSRT_TEST_PG_URL"]
PG_ADMIN = os.environ["NURBSRT_TEST_PG_ADMIN"]
PORT = os.environ["NURBSRT_TEST_PG_PORT"]


def serve(tmp_path, store, data=None):
    data = data or tmp_path / "data"
    r = subprocess.run([os.environ["NURBSRT_BIN"], "serve", "--port", "0", "--data-dir", str(data),
                        "--job-store", store], capture_output=True, timeout=60)
    return r.returncode, r.stderr.decode(errors="replace")


def psql(url, sql):
    return subprocess.run(["psql", "-qtA", url, "-c", sql], capture_output=True, text=True, check=True).stdout


def closed_port():
    s = socket.socket()
    s.bind(("127.0.0.1", 0))
    port = s.getsockname()[1]
    s.close()  # nothing listens there now
    return port


def test_unreachable_database(tmp_path):
    rc, err = serve(tmp_path, f"postgresql://postgres@127.0.0.1:{closed_port()}/nurbsrt")
    assert rc != 0
    assert "cannot connect" in err and "Connection refused" in err, err[-600:]


def test_wrong_password_is_named_but_not_shown(tmp_path):
    rc, err = serve(tmp_path, f"postgresql://postgres:not-the-password@127.0.0.1:{PORT}/nurbsrt")
    assert rc != 0
    assert "password authentication failed" in err, err[-600:]
    assert "not-the-password" not in err and "postgres:***@" in err, err[-600:]


def test_schema_newer_than_the_binary(tmp_path):
    psql(PG_ADMIN, "CREATE DATABASE newer")
    newer = PG_ADMIN.rsplit("/", 1)[0] + "/newer"
    psql(newer, "CREATE TABLE schema_version (version INTEGER NOT NULL); INSERT INTO schema_version VALUES (99)")
    rc, err = serve(tmp_path, newer)
    assert rc != 0
    assert "schema version 99" in err and "newer than this nurbsrt" in err, err[-600:]


def test_job_directory_not_writable(tmp_path):
    data = tmp_path / "data"
    data.mkdir()
    (data / "jobs").write_text("a file where the job directory should be")
    rc, err = serve(tmp_path, PG_URL, data)
    assert rc != 0
    assert "job directory" in err, err[-600:]
    if os.geteuid() != 0:  # root ignores permissions: only a non-root run checks this case
        (data / "jobs").unlink()
        (data / "jobs").mkdir(mode=0o500)
        rc, err = serve(tmp_path, PG_URL, data)
        assert rc != 0 and "not writable" in err, err[-600:]
