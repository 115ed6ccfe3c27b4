"""Batch-job conversions to the mesh and NURBS formats (stl, glb, json): the job
runner and the conversion formats meet here. Each artifact parses, with the
same checks as the synchronous conversions, and agrees with the input's faces."""
import json
import os

import jsonschema

import requests

from conftest import BEARING, MODELS, REPO, SCREW, TIMEOUT, check_problem, generated_fixture, post_raw
from test_conversions import parse_glb, parse_stl
from test_jobs import accepted, download, png_size, submit, wait_finished, wait_for

NURBS_SCHEMA = json.loads((REPO / "api_schema" / "nurbs_scene.schema.json").read_text())


def test_job_converts_to_stl_glb_and_nurbs_json(url):
    cornetta = MODELS / "step" / "bug27693_cornetta-step.stp"
    files = [("bearing.iges", BEARING.read_bytes()),
             ("model.stp", (cornetta if cornetta.is_file() else SCREW).read_bytes())]
    outputs = [{"file": f, "type": "conversion", "format": fmt} for f in (0, 1) for fmt in ("stl", "glb", "json")]
    job = wait_finished(url, accepted(submit(url, files, {"outputs": outputs}))["id"])
    assert job["state"] == "succeeded", json.dumps(job)[:800]
    assert len(job["outputs"]) == 6
    by = {(o["file"], o["format"]): o for o in job["outputs"]}
    for f in (0, 1):
        art = download(url, by[(f, "stl")])
        assert by[(f, "stl")]["artifact"]["content_type"] == "model/stl"
        assert len(parse_stl(art)) > 100

        gltf, _ = parse_glb(download(url, by[(f, "glb")]))
        assert by[(f, "glb")]["artifact"]["content_type"] == "model/gltf-binary"
        assert gltf["meshes"] and gltf["accessors"]

        scene = json.loads(download(url, by[(f, "json")]))
        jsonschema.Draft202012Validator(NURBS_SCHEMA).validate(scene)
        assert scene["patches"] == len(scene["faces"]) > 0


# Each format's name in a report, as POST /v1/conversions answers it (test_conversions.py checks those).
FORMAT_NAMES = {"step": "STEP", "iges": "IGES", "stl": "STL", "glb": "GLB", "json": "NURBS-JSON", "brep": "BREP",
                "vrml": "VRML"}


def test_job_converts_to_every_format_named_as_posted_ones_and_takes_a_brep_input(url):
    outputs = [{"file": 0, "type": "conversion", "format": fmt} for fmt in FORMAT_NAMES]
    job = wait_finished(url, accepted(submit(url, [("screw.step", SCREW.read_bytes())], {"outputs": outputs}))["id"])
    assert job["state"] == "succeeded", json.dumps(job)[:800]
    by = {o["format"]: o for o in job["outputs"]}
    assert {f: by[f]["report"]["output_format"] for f in FORMAT_NAMES} == FORMAT_NAMES
    assert {by[f]["report"]["input_format"] for f in FORMAT_NAMES} == {"STEP"}
    # The same name as the synchronous conversion of the same file answers.
    sync = post_raw(url, "/v1/conversions", SCREW.read_bytes(), params={"format": "json"},
                    headers={"Accept": "application/json"})
    assert sync.status_code == 200, sync.text[:300]
    assert sync.json()["output_format"] == by["json"]["report"]["output_format"]
    assert by["brep"]["artifact"]["name"].endswith(".brep")
    assert by["vrml"]["artifact"]["name"].endswith(".wrl")
    assert by["vrml"]["artifact"]["content_type"] == "model/vrml"
    # Each conversion output reports its fidelity, as POST /v1/conversions does.
    f = by["brep"]["report"]["fidelity"]
    assert f["source"]["geometry"]["faces"] == f["output"]["geometry"]["faces"] == 10
    assert by["vrml"]["report"]["fidelity"]["output"]["deviation_in_mm"]["points"] > 0
    brep = download(url, by["brep"])
    assert b"CASCADE Topology V" in brep[:200]
    assert download(url, by["vrml"]).startswith(b"#VRML V2.0 utf8")
    # The BREP artifact as a job's input: recognised by content, converted back to STEP.
    job = wait_finished(url, accepted(submit(url, [("screw.brep", brep)],
                                             {"outputs": [{"file": 0, "type": "conversion", "format": "step"}]}))["id"])
    assert job["state"] == "succeeded", json.dumps(job)[:800]
    assert job["files"][0]["format"] == "BREP"
    assert download(url, job["outputs"][0]).startswith(b"ISO-10303-21;")


def test_job_conversion_options_as_post_conversions(url):
    """A conversion output takes the options of POST /v1/conversions (units, step_schema,
    iges_mode, deflection, angular_deflection, strict), read by the same parser: the unit asked is written, a
    coarse deflection is warned, and strict fails that output (strict_refused, no artifact)
    while the others succeed; an option the format does not take refuses the job (400)."""
    freeform = generated_fixture("freeform_bspline").read_bytes()
    outputs = [
        {"file": 0, "type": "conversion", "format": "step", "options": {"units": "cm", "step_schema": "ap242"}},
        {"file": 0, "type": "conversion", "format": "stl", "options": {"deflection": 0.1}},
        {"file": 0, "type": "conversion", "format": "stl", "options": {"deflection": 0.1, "strict": True}},
    ]
    job = wait_finished(url, accepted(submit(url, [("ff.step", freeform)], {"outputs": outputs}))["id"])
    step, coarse, strict = job["outputs"]
    assert step["state"] == "succeeded", json.dumps(step)[:600]
    assert step["report"]["fidelity"]["output"]["units"] == "cm"
    data = download(url, step)
    assert b"AP242" in data[:2000] or b"ap242" in data[:2000].lower(), data[:600]
    assert coarse["state"] == "succeeded", json.dumps(coarse)[:600]
    assert any("the STL mesh lies up to" in w for w in coarse["report"]["warnings"]), coarse["report"]["warnings"]
    assert strict["state"] == "failed" and strict["error"]["code"] == "strict_refused", json.dumps(strict)[:600]
    assert "the STL mesh lies up to" in strict["error"]["message"]
    assert "artifact" not in strict
    r = submit(url, [("ff.step", freeform)],
               {"outputs": [{"file": 0, "type": "conversion", "format": "glb", "options": {"units": "inch"}}]})
    detail = check_problem(r, 400)["detail"]
    assert "output 0: option 'units' applies to STEP and IGES outputs only" in detail, detail


def test_job_writes_obj_and_its_mtl_as_two_artifacts_that_work_side_by_side(url, tmp_path):
    """OBJ as a job output: `<output>.obj` and `<output>.mtl`, the .obj's mtllib naming the .mtl's artifact
    name (downloaded side by side, every material it uses is defined there), with the fidelity report of the
    other mesh outputs; reused per file by a later job."""
    data = generated_fixture("assembly").read_bytes() + b"\n" * (os.getpid() % 997 + 11)  # bytes of this run
    spec = {"outputs": [{"file": 0, "type": "conversion", "format": "obj"}]}
    job = wait_finished(url, accepted(submit(url, [("two brackets.step", data)], spec))["id"])
    assert job["state"] == "succeeded", json.dumps(job)[:800]
    out = job["outputs"][0]
    assert out["format"] == "obj"
    names = [(a["name"], a["content_type"]) for a in out["artifacts"]]
    assert names == [("0-conversion-0.obj", "model/obj"), ("0-conversion-0.mtl", "model/mtl")], names
    assert out["artifact"] == out["artifacts"][0]
    for a in out["artifacts"]:
        (tmp_path / a["name"]).write_bytes(download(url, {"artifact": a}))
    obj = (tmp_path / "0-conversion-0.obj").read_text()
    mtllib = [line.split(None, 1)[1] for line in obj.splitlines() if line.startswith("mtllib ")]
    assert mtllib == ["0-conversion-0.mtl"], mtllib
    assert (tmp_path / mtllib[0]).is_file()
    used = {line.split(None, 1)[1] for line in obj.splitlines() if line.startswith("usemtl ")}
    defined = {line.split(None, 1)[1] for line in (tmp_path / mtllib[0]).read_text().splitlines()
               if line.startswith("newmtl ")}
    assert used and used <= defined, (used, defined)
    assert obj.count("\ng two_brackets/bracket\n") == 2, obj[:400]
    report = out["report"]
    assert report["output_format"] == "OBJ"
    assert report["fidelity"]["output"]["deviation_in_mm"]["face_instances"] == 14
    assert report["fidelity"]["output"]["asked"]["angular_deflection"] == 0.35
    assert report["artifacts"] == [{"name": a["name"], "bytes": a["bytes"]} for a in out["artifacts"]]
    assert job["statistics"]["artifacts"] == 2
    assert job["statistics"]["artifact_bytes"] == sum(a["bytes"] for a in out["artifacts"])
    # The same file and options again: both files reused, byte for byte.
    again = wait_finished(url, accepted(submit(url, [("again.step", data)], spec))["id"])
    assert again["state"] == "succeeded" and again["statistics"]["reused"] == 1, json.dumps(again)[:600]
    for a, b in zip(out["artifacts"], again["outputs"][0]["artifacts"]):
        assert download(url, {"artifact": a}) == download(url, {"artifact": b})


def test_job_document_echoes_each_conversions_options_resolved(url):
    """Each conversion output's options as resolved: the format's every option with its default named
    (units source, step_schema, iges_mode, deflection, angular_deflection, strict), as given otherwise."""
    outputs = [{"file": 0, "type": "conversion", "format": "stp"},
               {"file": 0, "type": "conversion", "format": "igs", "options": {"units": "inch", "iges_mode": "faces"}},
               {"file": 0, "type": "conversion", "format": "glb", "options": {"angular_deflection": 0.5}},
               {"file": 0, "type": "conversion", "format": "json", "options": {"strict": True}}]
    job = accepted(submit(url, [("screw.step", SCREW.read_bytes())], {"outputs": outputs}))
    expected = [{"format": "step", "units": "source", "step_schema": "ap214", "strict": False},
                {"format": "iges", "units": "inch", "iges_mode": "faces", "strict": False},
                {"format": "glb", "deflection": 0.002, "angular_deflection": 0.5, "strict": False},
                {"format": "json", "strict": True}]
    assert [o["options"] for o in job["outputs"]] == expected  # in the 202 already
    job = wait_finished(url, job["id"])
    assert job["state"] == "succeeded", json.dumps(job)[:800]
    assert [o["options"] for o in job["outputs"]] == expected
    assert job["outputs"][2]["report"]["fidelity"]["output"]["asked"]["angular_deflection"] == 0.5


def test_angular_deflection_is_asked_of_brepmesh_and_range_checked(url):
    """angular_deflection (radians) reaches BRepMesh: a coarser angle makes fewer triangles of a curved part,
    and the fidelity report says what was asked beside the deviation achieved; outside [0.01, pi/2], or with a
    format that is no mesh, 400 naming the option, in a conversion and in a job."""
    data = SCREW.read_bytes()
    answers = {}
    for angle in (0.1, 1.0):
        r = post_raw(url, "/v1/conversions", data, params={"format": "stl", "angular_deflection": str(angle)},
                     headers={"Accept": "application/json"})
        assert r.status_code == 200, r.text[:300]
        answers[angle] = r.json()
    fine, coarse = answers[0.1], answers[1.0]
    assert fine["triangles"] > coarse["triangles"] > 0, (fine["triangles"], coarse["triangles"])
    for angle, j in answers.items():
        out = j["fidelity"]["output"]
        assert out["asked"]["angular_deflection"] == angle and out["asked"]["deflection"] == 0.002
        assert out["asked"]["deflection_mm"] > 0 and out["deviation_in_mm"]["max"] >= 0
    for params, what in (({"format": "stl", "angular_deflection": "0.001"}, "option 'angular_deflection' must be"),
                         ({"format": "obj", "angular_deflection": "2"}, "option 'angular_deflection' must be"),
                         ({"format": "step", "angular_deflection": "0.2"},
                          "option 'angular_deflection' applies to STL, GLB, VRML and OBJ outputs only")):
        detail = check_problem(post_raw(url, "/v1/conversions", data, params=params), 400)["detail"]
        assert what in detail, detail
    r = submit(url, [("screw.step", data)], {"outputs": [
        {"file": 0, "type": "conversion", "format": "vrml", "options": {"angular_deflection": 0}}]})
    detail = check_problem(r, 400)["detail"]
    assert "output 0: option 'angular_deflection' must be" in detail, detail


def test_separate_views_download_as_each_is_written(own_server):
    """A job's separate views: each view's artifact is listed (with its view) and downloads while the output
    still renders the next one; the output's progress counts the views done."""
    s = own_server(args=["--workers", "1", "--job-runners", "1", "--render-threads", "1"])
    options = {"width": 1200, "height": 1200, "antialias": 16, "shadows": True, "edges": True,
               "views": ["front", "top", "iso"], "layout": "separate"}
    job = accepted(submit(s.url, [("s.step", SCREW.read_bytes())],
                          {"outputs": [{"file": 0, "type": "render", "options": options}], "force": True}))
    job = wait_for(s.url, job["id"],
                   lambda j: j["state"] in ("succeeded", "failed") or j["outputs"][0].get("artifacts"),
                   timeout=180, what="the first view written")
    out = job["outputs"][0]
    assert job["state"] == "running" and out["state"] == "running", json.dumps(job)[:600]
    first = out["artifacts"][0]
    assert (first["name"], first["view"]) == ("0-render-0.front.png", "front")
    assert png_size(download(s.url, {"artifact": first})) == (1200, 1200)
    assert job["statistics"]["artifacts"] >= 1 and job["statistics"]["succeeded"] == 0
    assert out["progress"] >= 0.333, out["progress"]  # PostgreSQL keeps 6 digits
    # A view not written yet: 404 naming its output's state.
    missing = requests.get(f"{s.url}/v1/jobs/{job['id']}/artifacts/0-render-0.iso.png", timeout=TIMEOUT)
    assert "is not available: its output is running" in check_problem(missing, 404)["detail"]
    assert requests.delete(f"{s.url}/v1/jobs/{job['id']}", timeout=TIMEOUT).status_code == 202


def test_synchronous_separate_render_still_answers_a_zip(url):
    import io
    import zipfile
    r = post_raw(url, "/v1/renders", SCREW.read_bytes(),
                 params={"width": "64", "height": "48", "views": "front,iso", "layout": "separate"})
    assert r.status_code == 200 and r.headers["Content-Type"] == "application/zip", r.text[:300]
    assert zipfile.ZipFile(io.BytesIO(r.content)).namelist() == ["front.png", "iso.png"]


def test_separate_views_are_reused_per_file_unless_forced(url):
    """Artifact reuse keeps each view's file under its own key: the same file, options and views again are
    served from them (every view, byte for byte, no read); `force` renders them anew."""
    data = SCREW.read_bytes() + b"\n" * (os.getpid() % 991 + 1013)  # bytes of this run
    spec = {"outputs": [{"file": 0, "type": "render",
                         "options": {"width": 48, "height": 40, "views": ["front", "iso"], "layout": "separate"}}]}
    first = wait_finished(url, accepted(submit(url, [("a.step", data)], spec))["id"])
    again = wait_finished(url, accepted(submit(url, [("b.step", data)], spec))["id"])
    forced = wait_finished(url, accepted(submit(url, [("c.step", data)], {**spec, "force": True}))["id"])
    assert [j["state"] for j in (first, again, forced)] == ["succeeded"] * 3
    assert (first["statistics"]["reused"], again["statistics"]["reused"], forced["statistics"]["reused"]) == (0, 1, 0)
    # Made anew: rendered from the cached scene (no read either), its statistics without `reused`.
    assert again["statistics"]["reads"] == 0 and "reused" not in forced["outputs"][0]["statistics"]
    for job in (again, forced):
        files = job["outputs"][0]["artifacts"]
        assert [a["view"] for a in files] == ["front", "iso"]
        for a, b in zip(first["outputs"][0]["artifacts"], files):
            assert download(url, {"artifact": a}) == download(url, {"artifact": b})
