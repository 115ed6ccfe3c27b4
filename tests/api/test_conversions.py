"""POST /v1/conversions: STEP <-> IGES in an isolated child process."""
import base64

import requests

from conftest import BEARING, SCREW, TIMEOUT, check_problem, post_raw, validate


def test_step_to_iges_raw(url):
    r = post_raw(url, "/v1/conversions", SCREW.read_bytes(), params={"format": "iges"})
    assert r.status_code == 200, r.text[:300]
    assert r.headers["Content-Type"] == "model/iges"
    assert "converted.igs" in r.headers["Content-Disposition"]
    assert r.content[72:73] == b"S"  # first IGES record: Start section
    # The converted file renders.
    r2 = post_raw(url, "/v1/renders", r.content, params={"width": 48, "height": 48})
    assert r2.status_code == 200, r2.text[:300]


def test_iges_to_step_json(url):
    r = requests.post(url + "/v1/conversions", files={"file": ("b.iges", BEARING.read_bytes()),
                                                      "options": (None, '{"format": "step"}')},
                      headers={"Accept": "application/json"}, timeout=TIMEOUT)
    assert r.status_code == 200, r.text[:300]
    body = r.json()
    validate(body, "ConversionResponse")
    assert (body["input_format"], body["output_format"]) == ("IGES", "STEP")
    assert body["faces"] > 0
    assert base64.b64decode(body["data_base64"]).startswith(b"ISO-10303-21;")
    assert body["timings_ms"]["total"] >= body["timings_ms"]["read"]


def test_conversion_errors(url):
    check_problem(post_raw(url, "/v1/conversions", SCREW.read_bytes()), 400, "invalid_argument")  # no format
    check_problem(post_raw(url, "/v1/conversions", SCREW.read_bytes(), params={"format": "dwg"}), 400)
    check_problem(post_raw(url, "/v1/conversions", SCREW.read_bytes(), params={"format": "stl"}), 415)
    check_problem(post_raw(url, "/v1/conversions", b"hello", params={"format": "step"}), 415)
    check_problem(post_raw(url, "/v1/conversions", SCREW.read_bytes()[:1500], params={"format": "iges"}), 422)
