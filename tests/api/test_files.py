"""Stored files (/v1/files): upload once (multipart or raw), format by content,
SHA-256, dedupe (same id, stored once), get/list/paging/content/delete/404,
the quota (507), pinning and expiry; renders, conversions and jobs by
file_id answering as an upload would; the ETag/304 of a stored file's render;
a broken file refused with the problem its render gets."""
import hashlib
import json
import time

import requests

from conftest import BEARING, SCREW, TIMEOUT, check_problem, post_raw, validate

TRUNCATED_STEP = SCREW.read_bytes()[:1500]  # a STEP header, then nothing readable


def variant(n):
    """Screw bytes no other test uses: trailing newlines change the SHA-256, not the model."""
    return SCREW.read_bytes() + b"\n" * (1000 + n)


def fresh(url, data):
    """Removes a stored copy of `data` left by an earlier run, so the next upload creates it."""
    requests.delete(f"{url}/v1/files/{hashlib.sha256(data).hexdigest()}", timeout=TIMEOUT)
    return data


def upload(url, data, filename="part.step", fields=None):
    files = [("file", (filename, data, "application/octet-stream"))]
    files += [(k, (None, v)) for k, v in (fields or {}).items()]
    return requests.post(url + "/v1/files", files=files, timeout=TIMEOUT)


def stored(resp, status=201):
    assert resp.status_code == status, resp.text[:400]
    body = resp.json()
    validate(body, "StoredFile")
    assert resp.headers["Location"] == body["url"] == f"/v1/files/{body['id']}"
    return body


def stored_bytes(url):
    r = requests.get(url + "/v1/files", params={"limit": 1}, timeout=TIMEOUT)
    assert r.status_code == 200
    validate(r.json(), "StoredFileList")
    return r.json()["stored_bytes"]


def test_upload_multipart_and_raw(url):
    data = fresh(url, variant(1))
    f = stored(upload(url, data, "screw.step"))
    assert f["id"] == f["sha256"] == hashlib.sha256(data).hexdigest()
    assert f["format"] == "STEP" and f["bytes"] == len(data) and f["filename"] == "screw.step"
    assert f["pinned"] is False and f["expires_at"] > f["created_at"]
    s = f["summary"]
    assert s["faces"] > 0 and s["units"] and s["bodies"] >= 1
    assert all(lo <= hi for lo, hi in zip(s["bbox"]["min"], s["bbox"]["max"]))

    raw = fresh(url, variant(2))
    r = post_raw(url, "/v1/files", raw, params={"filename": "named.stp"})
    assert stored(r)["filename"] == "named.stp"
    raw2 = fresh(url, variant(3))
    r = post_raw(url, "/v1/files", raw2, headers={"Content-Disposition": 'attachment; filename="cd.step"'})
    assert stored(r)["filename"] == "cd.step"


def test_content_comes_back_under_its_name_byte_for_byte(url):
    # screw.step stays .step (not .stp), a UTF-8 name stays UTF-8 in RFC 8187's form,
    # with a printable-ASCII stand-in for clients that only read filename="...".
    for n, (name, quoted, encoded) in enumerate([("screw.step", "screw.step", "screw.step"),
                                                 ("Gehäuse v2.STEP", "Geh__use v2.STEP", "Geh%C3%A4use%20v2.STEP")]):
        data = fresh(url, variant(60 + n))
        f = stored(post_raw(url, "/v1/files", data, params={"filename": name}))
        assert f["filename"] == name
        c = requests.get(f"{url}/v1/files/{f['id']}/content", timeout=TIMEOUT)
        assert c.status_code == 200 and c.content == data and c.headers["Content-Type"] == "model/step"
        assert c.headers["Content-Disposition"] == f"attachment; filename=\"{quoted}\"; filename*=UTF-8''{encoded}"


def test_format_is_sniffed_not_taken_from_the_name(url):
    data = fresh(url, variant(4))
    f = stored(upload(url, data, "looks-like.igs"))
    assert f["format"] == "STEP" and f["filename"] == "looks-like.igs"
    check_problem(upload(url, b"solid cube\nendsolid\n", "x.step"), 415, "unsupported_format")
    check_problem(upload(url, b"", "empty.step"), 400, "invalid_argument")


def test_same_bytes_are_stored_once(url):
    data = fresh(url, variant(5))
    first = stored(upload(url, data))
    used = stored_bytes(url)
    again = stored(upload(url, data, "other-name.step"), 200)
    assert again["id"] == first["id"] and again["created_at"] == first["created_at"]
    assert again["filename"] == first["filename"]  # the stored record
    assert stored_bytes(url) == used


def test_get_content_list_and_delete(url):
    datas = [fresh(url, variant(10 + i)) for i in range(3)]
    ids = [stored(upload(url, d, f"p{i}.step"))["id"] for i, d in enumerate(datas)]
    r = requests.get(f"{url}/v1/files/{ids[0]}", timeout=TIMEOUT)
    assert r.status_code == 200
    validate(r.json(), "StoredFile")
    assert r.json()["filename"] == "p0.step"

    c = requests.get(f"{url}/v1/files/{ids[0]}/content", timeout=TIMEOUT)
    assert c.status_code == 200 and c.content == datas[0]
    assert c.headers["Content-Type"] == "model/step"
    assert c.headers["ETag"] == f'"{ids[0]}"'
    # The name it was stored under, byte for byte (RFC 6266 with RFC 8187's UTF-8 form).
    assert c.headers["Content-Disposition"] == "attachment; filename=\"p0.step\"; filename*=UTF-8''p0.step"
    again = requests.get(f"{url}/v1/files/{ids[0]}/content", headers={"If-None-Match": c.headers["ETag"]},
                         timeout=TIMEOUT)
    assert again.status_code == 304 and again.content == b""

    for order in ("newest", "oldest"):
        seen, cursor = [], None
        while True:
            params = {"limit": 2, "order": order, **({"cursor": cursor} if cursor else {})}
            page = requests.get(url + "/v1/files", params=params, timeout=TIMEOUT)
            assert page.status_code == 200
            body = page.json()
            validate(body, "StoredFileList")
            assert len(body["files"]) <= 2
            seen += [f["id"] for f in body["files"]]
            cursor = body["next_cursor"]
            if not cursor:
                break
        mine = [i for i in seen if i in ids]
        assert mine == (ids[::-1] if order == "newest" else ids)
    check_problem(requests.get(url + "/v1/files", params={"cursor": "nope"}, timeout=TIMEOUT), 400,
                  "invalid_argument")
    check_problem(requests.get(url + "/v1/files", params={"limit": 0}, timeout=TIMEOUT), 400, "invalid_argument")

    r = requests.delete(f"{url}/v1/files/{ids[1]}", timeout=TIMEOUT)
    assert r.status_code == 204 and r.content == b""
    body = check_problem(requests.get(f"{url}/v1/files/{ids[1]}", timeout=TIMEOUT), 404, "not_found")
    assert ids[1] in body["detail"]
    check_problem(requests.delete(f"{url}/v1/files/{ids[1]}", timeout=TIMEOUT), 404, "not_found")
    check_problem(requests.get(f"{url}/v1/files/{ids[1]}/content", timeout=TIMEOUT), 404, "not_found")
    check_problem(requests.get(f"{url}/v1/files/..%2Fjobs.db", timeout=TIMEOUT), 404, "not_found")


def test_quota_exceeded_is_507(own_server):
    # 0.1 MiB = 104857 bytes: room for one screw (88552 bytes and a few newlines), not two.
    s = own_server(args=["--max-stored-mb", "0.1"])
    first = stored(upload(s.url, variant(20)))
    used = stored_bytes(s.url)
    assert used == first["bytes"]
    body = check_problem(upload(s.url, variant(21)), 507, "limit_exceeded")
    assert "quota" in body["detail"] and str(104857) in body["detail"]
    assert stored_bytes(s.url) == used
    stored(upload(s.url, variant(20)), 200)  # the same bytes need no room
    assert requests.delete(f"{s.url}/v1/files/{first['id']}", timeout=TIMEOUT).status_code == 204
    stored(upload(s.url, variant(21)))


def test_pin_and_expiry(own_server):
    s = own_server(args=["--job-retention", "2"])
    pinned = stored(upload(s.url, variant(30), fields={"pinned": "true"}))
    assert pinned["pinned"] is True and pinned["expires_at"] is None
    loose = stored(upload(s.url, variant(31)))
    late = stored(upload(s.url, variant(32)))
    r = requests.patch(f"{s.url}/v1/files/{late['id']}", json={"pinned": True}, timeout=TIMEOUT)
    assert r.status_code == 200
    validate(r.json(), "StoredFile")
    assert r.json()["pinned"] is True and r.json()["expires_at"] is None
    check_problem(requests.patch(f"{s.url}/v1/files/{late['id']}", json={"pinned": "yes"}, timeout=TIMEOUT), 400,
                  "invalid_argument")
    check_problem(requests.patch(f"{s.url}/v1/files/{late['id']}", json={"filename": "x"}, timeout=TIMEOUT), 400,
                  "invalid_argument")
    check_problem(requests.patch(f"{s.url}/v1/files/{'0' * 64}", json={"pinned": True}, timeout=TIMEOUT), 404,
                  "not_found")
    deadline = time.monotonic() + 20
    while requests.get(f"{s.url}/v1/files/{loose['id']}", timeout=TIMEOUT).status_code != 404:
        assert time.monotonic() < deadline, "the unpinned file never expired"
        time.sleep(0.2)
    for f in (pinned, late):
        assert requests.get(f"{s.url}/v1/files/{f['id']}", timeout=TIMEOUT).status_code == 200
    assert not (s.data_dir / "files" / f"{loose['id']}.cad").exists()


def test_render_by_file_id_equals_render_by_upload(url):
    data = fresh(url, variant(40))
    file_id = stored(upload(url, data))["id"]
    opts = {"view": "front", "width": 64, "height": 48}
    by_upload = post_raw(url, "/v1/renders", data, params=opts)
    by_id = requests.post(url + "/v1/renders", json={"file_id": file_id, **opts}, timeout=TIMEOUT)
    assert by_upload.status_code == 200 and by_id.status_code == 200, by_id.text[:300]
    assert by_id.headers["Content-Type"] == by_upload.headers["Content-Type"] == "image/png"
    assert by_id.content == by_upload.content

    j_upload = post_raw(url, "/v1/renders", data, params=opts, headers={"Accept": "application/json"})
    j_id = requests.post(url + "/v1/renders", json={"file_id": file_id, **opts},
                         headers={"Accept": "application/json"}, timeout=TIMEOUT)
    assert j_id.status_code == 200
    validate(j_id.json(), "RenderResponse")
    s_up, s_id = j_upload.json()["statistics"], j_id.json()["statistics"]
    assert s_id["faces"] == s_up["faces"]
    assert s_id["cache"] == "hit"  # the upload imported it: no second import
    for stage in ("read", "nurbs_convert", "mesh"):
        assert s_id["timings_ms"][stage] == 0

    # Multipart with a file_id field and an options part.
    mp = requests.post(url + "/v1/renders", files=[("file_id", (None, file_id)),
                                                   ("options", (None, json.dumps(opts), "application/json"))],
                       timeout=TIMEOUT)
    assert mp.status_code == 200 and mp.content == by_upload.content


def test_stored_file_render_etag_and_304(url):
    file_id = stored(upload(url, fresh(url, variant(41))))["id"]
    body = {"file_id": file_id, "width": 40, "height": 30}
    first = requests.post(url + "/v1/renders", json=body, timeout=TIMEOUT)
    assert first.status_code == 200
    etag = first.headers["ETag"]
    assert etag.startswith('"') and not etag.startswith("W/")
    second = requests.post(url + "/v1/renders", json=body, timeout=TIMEOUT)
    assert second.headers["ETag"] == etag and second.content == first.content  # strong: same bytes
    cond = requests.post(url + "/v1/renders", json=body, headers={"If-None-Match": etag}, timeout=TIMEOUT)
    assert cond.status_code == 304 and cond.content == b"" and cond.headers["ETag"] == etag
    other = requests.post(url + "/v1/renders", json={**body, "width": 41}, headers={"If-None-Match": etag},
                          timeout=TIMEOUT)
    assert other.status_code == 200 and other.headers["ETag"] != etag
    # JSON answers carry timings and a request id: no tag.
    j = requests.post(url + "/v1/renders", json=body, headers={"Accept": "application/json"}, timeout=TIMEOUT)
    assert j.status_code == 200 and "ETag" not in j.headers


def test_conversion_by_file_id(url):
    data = fresh(url, variant(42))
    file_id = stored(upload(url, data, "bolt.step"))["id"]
    by_upload = post_raw(url, "/v1/conversions", data, params={"format": "stl"},
                         headers={"Accept": "application/json"})
    by_id = requests.post(url + "/v1/conversions", json={"file_id": file_id, "format": "stl"},
                          headers={"Accept": "application/json"}, timeout=TIMEOUT)
    assert by_id.status_code == 200, by_id.text[:300]
    validate(by_id.json(), "ConversionResponse")
    for key in ("input_format", "output_format", "faces", "triangles", "data_base64"):
        assert by_id.json()[key] == by_upload.json()[key], key
    # A download is named after the stored file.
    d = requests.post(url + "/v1/conversions", files=[("file_id", (None, file_id)), ("format", (None, "iges"))],
                      timeout=TIMEOUT)
    assert d.status_code == 200
    assert d.headers["Content-Disposition"] == "attachment; filename=\"bolt.igs\"; filename*=UTF-8''bolt.igs"


def test_job_by_file_id_survives_the_file_deleted(url):
    file_id = stored(upload(url, fresh(url, variant(43)), "jobbed.step"))["id"]
    spec = {"outputs": [{"file": 0, "type": "render", "options": {"width": 32, "height": 24}},
                        {"file": "jobbed.step", "type": "conversion", "format": "iges"}]}
    r = requests.post(url + "/v1/jobs", files=[("file_id", (None, file_id)),
                                               ("job", (None, json.dumps(spec), "application/json"))],
                      timeout=TIMEOUT)
    assert r.status_code == 202, r.text[:400]
    job = r.json()
    validate(job, "Job")
    assert job["files"][0]["filename"] == "jobbed.step" and job["files"][0]["format"] == "STEP"
    # The job copied the bytes when it was accepted.
    assert requests.delete(f"{url}/v1/files/{file_id}", timeout=TIMEOUT).status_code == 204
    deadline = time.monotonic() + 90
    while job["state"] not in ("succeeded", "failed"):
        assert time.monotonic() < deadline, json.dumps(job)[:600]
        time.sleep(0.1)
        job = requests.get(f"{url}/v1/jobs/{job['id']}", timeout=TIMEOUT).json()
    assert job["state"] == "succeeded", json.dumps(job)[:600]


def test_broken_file_gets_the_render_problem_and_is_not_stored(url):
    by_render = post_raw(url, "/v1/renders", TRUNCATED_STEP)
    by_file = post_raw(url, "/v1/files", TRUNCATED_STEP)
    b_render = check_problem(by_render, by_render.status_code)
    b_file = check_problem(by_file, by_render.status_code, b_render["code"])
    assert b_render["code"] in ("unreadable_file", "no_faces")
    assert b_file["detail"] == b_render["detail"] and b_file["title"] == b_render["title"]
    check_problem(requests.get(f"{url}/v1/files/{hashlib.sha256(TRUNCATED_STEP).hexdigest()}", timeout=TIMEOUT),
                  404, "not_found")
    assert requests.get(url + "/healthz", timeout=TIMEOUT).status_code == 200  # the process stays up


def test_unknown_file_id_is_404_naming_it(url):
    missing = "f" * 64
    for path, body in (("/v1/renders", {"file_id": missing}), ("/v1/conversions", {"file_id": missing,
                                                                                   "format": "stl"})):
        p = check_problem(requests.post(url + path, json=body, timeout=TIMEOUT), 404, "not_found")
        assert missing in p["detail"]
    spec = {"outputs": [{"file": 0, "type": "conversion", "format": "iges"}]}
    r = requests.post(url + "/v1/jobs", files=[("file_id", (None, missing)),
                                               ("job", (None, json.dumps(spec), "application/json"))],
                      timeout=TIMEOUT)
    assert missing in check_problem(r, 404, "not_found")["detail"]
    check_problem(requests.post(url + "/v1/renders", json={"file_id": "../../etc/passwd"}, timeout=TIMEOUT), 404,
                  "not_found")


def test_file_id_request_errors(url):
    check_problem(requests.post(url + "/v1/renders", json={"width": 10}, timeout=TIMEOUT), 400, "invalid_argument")
    check_problem(requests.post(url + "/v1/renders", json=[1], timeout=TIMEOUT), 400, "invalid_argument")
    both = requests.post(url + "/v1/renders", files=[("file", ("a.step", SCREW.read_bytes())),
                                                     ("file_id", (None, "f" * 64))], timeout=TIMEOUT)
    assert "not both" in check_problem(both, 400, "invalid_argument")["detail"]
    file_id = stored(upload(url, fresh(url, variant(44))))["id"]
    bad = requests.post(url + "/v1/renders", json={"file_id": file_id, "colour": "red"}, timeout=TIMEOUT)
    assert "colour" in check_problem(bad, 400, "invalid_argument")["detail"]
    # POST /v1/files takes the file itself.
    assert "itself" in check_problem(requests.post(url + "/v1/files", json={"file_id": file_id}, timeout=TIMEOUT),
                                     400, "invalid_argument")["detail"]
    check_problem(post_raw(url, "/v1/files", SCREW.read_bytes(), params={"colour": "red"}), 400, "invalid_argument")


def test_empty_file_id_is_400_everywhere_and_the_service_stays_up(url):
    """An empty id once read as "no stored file" and left the route without bytes: the process crashed."""
    job = json.dumps({"outputs": [{"file": 0, "type": "conversion", "format": "stl"}]})
    requests_to_send = [
        ("/v1/renders", {"json": {"file_id": ""}}),
        ("/v1/conversions", {"json": {"file_id": "", "format": "stl"}}),
        ("/v1/renders", {"files": [("file_id", (None, ""))]}),
        ("/v1/conversions", {"files": [("file_id", (None, "")), ("format", (None, "stl"))]}),
        ("/v1/files", {"files": [("file_id", (None, ""))]}),
        ("/v1/jobs", {"files": [("file_id", (None, "")), ("job", (None, job, "application/json"))]}),
    ]
    for path, kwargs in requests_to_send:
        r = requests.post(url + path, timeout=TIMEOUT, **kwargs)
        assert "'file_id' is empty" in check_problem(r, 400, "invalid_argument")["detail"], (path, r.text[:300])
    assert requests.get(url + "/healthz", timeout=TIMEOUT).status_code == 200


def test_iges_is_sniffed_too(url):
    data = fresh(url, BEARING.read_bytes())
    f = stored(post_raw(url, "/v1/files", data, params={"filename": "bearing.step"}))
    assert f["format"] == "IGES" and f["summary"]["faces"] > 0


def test_summary_lists_the_assembly_tree(url):
    """A stored assembly's summary carries its tree: the ids and names renders' `parts` take."""
    from conftest import MODELS
    import pytest
    as1 = MODELS / "step" / "as1-oc-214.stp"
    if not as1.exists():
        pytest.skip("../shared/models is absent: the assembly as1 is not there")
    body = stored(upload(url, fresh(url, as1.read_bytes()), "as1.stp"), 201)
    parts = body["summary"]["parts"]
    names = {p["name"] for p in parts}
    assert parts[0]["parent"] is None and "rod_1" in names and len(parts) > 10, parts[:3]
    child = next(p for p in parts if p["name"] == "rod_1")
    r = requests.post(
        url + "/v1/renders", json={"file_id": body["id"], "width": 64, "height": 48, "parts": {"only": [child["id"]]}},
        headers={"Accept": "application/json"}, timeout=TIMEOUT)
    assert r.status_code == 200, r.text[:300]
    assert r.json()["statistics"]["parts"]["hidden_faces"] == body["summary"]["faces"] - child["faces"]
