"""The Python client package (clients/python) installed as a user would, into a venv
(`python3 -m venv --system-site-packages`, `pip install --no-build-isolation`: no package
index needed), its own tests run there against this test run's service."""
import os
import pathlib
import shutil
import subprocess
import sys

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def venv(tmp_path_factory):
    where = tmp_path_factory.mktemp("client-venv")
    subprocess.run(["/usr/bin/python3", "-m", "venv", "--system-site-packages", str(where)], check=True, timeout=300)
    # Built from a copy: an in-tree build leaves build/ and *.egg-info in the checkout.
    source = shutil.copytree(ROOT / "clients" / "python", where / "source",
                             ignore=shutil.ignore_patterns("build", "*.egg-info", "__pycache__"))
    pip = subprocess.run([str(where / "bin" / "pip"), "install", "--quiet", "--no-build-isolation", "--no-index",
                          str(source)], capture_output=True, text=True, timeout=300)
    assert pip.returncode == 0, pip.stdout[-2000:] + pip.stderr[-2000:]
    return where


def test_client_package(url, venv):
    env = dict(os.environ, NURBSRT_URL=url)
    r = subprocess.run([str(venv / "bin" / "python"), "-m", "pytest", "-q", "-p", "no:cacheprovider",
                        str(ROOT / "clients" / "python" / "tests")], capture_output=True, text=True, env=env,
                       timeout=900, cwd=str(venv))
    sys.stdout.write(r.stdout[-3000:])
    assert r.returncode == 0, r.stdout[-4000:] + r.stderr[-2000:]
