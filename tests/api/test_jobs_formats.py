"""Batch-job conversions to the mesh and NURBS formats (stl, glb, json): the job
runner and the conversion formats meet here. Each artifact parses, with the
same checks as the synchronous conversions, and agrees with the input's faces."""
import json

import jsonschema

from conftest import BEARING, MODELS, REPO, SCREW, check_problem, generated_fixture, post_raw
from test_conversions import parse_glb, parse_stl
from test_jobs import accepted, download, submit, wait_finished

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
    iges_mode, deflection, strict), read by the same parser: the unit asked is written, a
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
