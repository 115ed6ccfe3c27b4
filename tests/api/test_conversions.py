"""POST /v1/conversions: STEP/IGES to STEP, IGES, STL, glb and NURBS JSON, in an
isolated child process. Every output is parsed here independently of nurbsrt."""
import base64
import json
import math
import struct

import jsonschema
import pytest
import requests

from conftest import (BEARING, MODELS, REPO, SCHEMA, SCREW, TIMEOUT, check_problem, generated_fixture, post_raw,
                      validate)

NURBS_SCHEMA = json.loads((REPO / "api_schema" / "nurbs_scene.schema.json").read_text())
ASSEMBLY = MODELS / "step" / "as1-oc-214.stp"  # an assembly with colours and instance names


def real_models():
    """OCCT's sample files (always installed) plus, when present, a real assembly of
    ../shared/models; its absence shows up as a skip, not as a silent pass."""
    return [pytest.param(SCREW, id="screw.step"), pytest.param(BEARING, id="bearing.iges"),
            pytest.param(ASSEMBLY, id="as1-oc-214.stp",
                         marks=pytest.mark.skipif(not ASSEMBLY.is_file(), reason=f"{ASSEMBLY} is absent"))]


def convert(url, path, fmt):
    r = post_raw(url, "/v1/conversions", path.read_bytes(), params={"format": fmt})
    assert r.status_code == 200, r.text[:300]
    return r


def parse_stl(data):
    """Binary STL: 80-byte header, uint32 count, then per triangle 12 float32 + uint16."""
    assert len(data) >= 84
    (count,) = struct.unpack_from("<I", data, 80)
    assert len(data) == 84 + 50 * count, (len(data), count)
    tris = [struct.unpack_from("<12f", data, 84 + 50 * k) for k in range(count)]
    for t in tris:
        assert all(math.isfinite(x) for x in t), t
    return tris


def parse_glb(data):
    """glTF 2.0 binary container: header, JSON chunk, BIN chunk (glTF spec 4.4)."""
    magic, version, length = struct.unpack_from("<4sII", data, 0)
    assert magic == b"glTF" and version == 2 and length == len(data)
    json_len, json_type = struct.unpack_from("<I4s", data, 12)
    assert json_type == b"JSON" and json_len % 4 == 0
    gltf = json.loads(data[20:20 + json_len])
    off = 20 + json_len
    bin_len, bin_type = struct.unpack_from("<I4s", data, off)
    assert bin_type == b"BIN\0"
    assert off + 8 + bin_len == len(data)
    assert gltf["asset"]["version"] == "2.0"
    assert gltf["buffers"][0]["byteLength"] <= bin_len
    for view in gltf["bufferViews"]:
        assert view["byteOffset"] + view["byteLength"] <= gltf["buffers"][0]["byteLength"]
    return gltf, data[off + 8:off + 8 + bin_len]


def test_step_to_iges_raw(url):
    r = convert(url, SCREW, "iges")
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


@pytest.mark.parametrize("model", real_models())
def test_stl(url, model):
    r = convert(url, model, "stl")
    assert r.headers["Content-Type"] == "model/stl"
    assert 'filename="converted.stl"' in r.headers["Content-Disposition"]
    tris = parse_stl(r.content)
    assert len(tris) > 100
    # Normals are unit length (or zero for a degenerate triangle); corners span a real box.
    for t in tris:
        n = math.sqrt(t[0] ** 2 + t[1] ** 2 + t[2] ** 2)
        assert n == 0 or abs(n - 1) < 1e-3, t
    # The mesh spans the model's box (from the NURBS dump of the same file), in millimetres.
    scene = convert(url, model, "json").json()
    lo, hi = scene["bbox"]["min"], scene["bbox"]["max"]
    diag = math.dist(lo, hi)
    for axis in range(3):
        cs = [t[3 + 3 * c + axis] for t in tris for c in range(3)]
        assert abs(min(cs) - lo[axis]) < 0.01 * diag and abs(max(cs) - hi[axis]) < 0.01 * diag, (axis, lo, hi)
    # The same triangle count as the JSON answer reports.
    j = requests.post(url + "/v1/conversions", data=model.read_bytes(), params={"format": "stl"},
                      headers={"Content-Type": "application/octet-stream", "Accept": "application/json"},
                      timeout=TIMEOUT).json()
    validate(j, "ConversionResponse")
    assert (j["output_format"], j["content_type"], j["triangles"]) == ("STL", "model/stl", len(tris))
    assert j["unmeshed_faces"] == 0
    assert j["timings_ms"]["mesh"] > 0


def test_stl_reports_faces_it_could_not_mesh(url):
    """trj3_s1-al-214.stp has 8 faces with broken trim loops that BRepMesh cannot
    triangulate (the import falls back to uv grids for them), and 2 whose every
    triangle has no area at float precision (left out): the answer says so."""
    model = MODELS / "step" / "trj3_s1-al-214.stp"
    if not model.is_file():
        pytest.skip(f"{model} is absent")
    j = requests.post(url + "/v1/conversions", data=model.read_bytes(), params={"format": "stl"},
                      headers={"Content-Type": "application/octet-stream", "Accept": "application/json"},
                      timeout=TIMEOUT).json()
    validate(j, "ConversionResponse")
    assert j["unmeshed_faces"] == 10 and j["faces"] == 94 and j["triangles"] > 0
    assert j["degenerate_triangles"] > 0
    # The missing faces are a warning, as on the CLI, and strict refuses them alike.
    assert "10 of 94 face(s) could not be meshed and are missing from the STL output" in j["warnings"], j["warnings"]
    detail = check_problem(post_raw(url, "/v1/conversions", model.read_bytes(), params={"format": "stl", "strict": "true"}),
                           422, "strict_refused")["detail"]
    assert "could not be meshed" in detail, detail


@pytest.mark.parametrize("model", real_models())
def test_glb(url, model):
    r = convert(url, model, "glb")
    assert r.headers["Content-Type"] == "model/gltf-binary"
    assert 'filename="converted.glb"' in r.headers["Content-Disposition"]
    gltf, _ = parse_glb(r.content)
    assert gltf["meshes"] and gltf["accessors"] and gltf["nodes"]
    positions = [gltf["accessors"][p["attributes"]["POSITION"]] for m in gltf["meshes"] for p in m["primitives"]]
    assert positions
    for acc in positions:
        assert acc["type"] == "VEC3" and acc["componentType"] == 5126 and acc["count"] >= 3
        # Metres (glTF): the sample models are under 2 m across, so no coordinate reaches 2.
        assert all(math.isfinite(x) and abs(x) < 2.0 for x in acc["min"] + acc["max"]), acc
    triangles = sum(gltf["accessors"][p["indices"]]["count"] // 3 for m in gltf["meshes"] for p in m["primitives"])
    assert triangles > 100


def test_glb_keeps_assembly_names_and_colours(url):
    if not ASSEMBLY.is_file():
        pytest.skip(f"{ASSEMBLY} is absent")
    gltf, _ = parse_glb(convert(url, ASSEMBLY, "glb").content)
    names = {n.get("name") for n in gltf["nodes"]}
    assert {"nut_1", "nut_2", "bolt_1", "rod_1"} <= names, names
    assert len({tuple(m["pbrMetallicRoughness"]["baseColorFactor"]) for m in gltf["materials"]}) > 1


def convert_json(url, path, fmt):
    r = requests.post(url + "/v1/conversions", data=path.read_bytes(), params={"format": fmt},
                      headers={"Content-Type": "application/octet-stream", "Accept": "application/json"},
                      timeout=TIMEOUT)
    assert r.status_code == 200, r.text[:300]
    body = r.json()
    validate(body, "ConversionResponse")
    return body


def test_step_and_iges_outputs_report_what_they_lose(url):
    """STEP and IGES outputs go through XDE: a STEP copy of the AS1 assembly keeps
    its colours, names and tree (no warnings); IGES has no assembly structure, and
    the answer says so."""
    if not ASSEMBLY.is_file():
        pytest.skip(f"{ASSEMBLY} is absent")
    assert convert_json(url, ASSEMBLY, "step")["warnings"] == []
    warnings = convert_json(url, ASSEMBLY, "iges")["warnings"]
    assert any(w.startswith("IGES has no assembly structure") for w in warnings), warnings
    assert not any("colour" in w for w in warnings), warnings
    # The file download says so too, in a header.
    r = requests.post(url + "/v1/conversions", data=ASSEMBLY.read_bytes(), params={"format": "iges"},
                      headers={"Content-Type": "application/octet-stream"}, timeout=TIMEOUT)
    assert r.status_code == 200, r.text[:300]
    count, _, listed = r.headers["X-Nurbsrt-Warnings"].partition("; ")
    assert int(count) == len(warnings) and json.loads(listed) == warnings
    r = requests.post(url + "/v1/conversions", data=ASSEMBLY.read_bytes(), params={"format": "step"},
                      headers={"Content-Type": "application/octet-stream"}, timeout=TIMEOUT)
    assert r.status_code == 200 and "X-Nurbsrt-Warnings" not in r.headers
    # Mesh outputs have nothing of the kind to report.
    assert convert_json(url, SCREW, "stl")["warnings"] == []


@pytest.mark.parametrize("model", real_models())
def test_nurbs_json(url, model):
    r = convert(url, model, "json")
    assert r.headers["Content-Type"].startswith("application/json")
    assert 'filename="converted.json"' in r.headers["Content-Disposition"]
    scene = r.json()
    jsonschema.Draft202012Validator(NURBS_SCHEMA).validate(scene)
    validate(scene, "NurbsScene")  # the copy inside the OpenAPI document accepts it too
    assert scene["patches"] == len(scene["faces"]) > 0
    assert [f["index"] for f in scene["faces"]] == list(range(1, len(scene["faces"]) + 1))
    for f in scene["faces"]:
        s = f["surface"]
        assert len(s["control_points"]) == s["num_u"] * s["num_v"]
        assert len(s["knots_u"]) == s["num_u"] + s["degree_u"] + 1
        assert len(s["knots_v"]) == s["num_v"] + s["degree_v"] + 1
    # The face count agrees with what the service reports for the same file.
    j = requests.post(url + "/v1/conversions", data=model.read_bytes(), params={"format": "json"},
                      headers={"Content-Type": "application/octet-stream", "Accept": "application/json"},
                      timeout=TIMEOUT).json()
    validate(j, "ConversionResponse")
    assert (j["output_format"], j["content_type"], j["faces"]) == ("NURBS-JSON", "application/json",
                                                                   scene["patches"])
    assert json.loads(base64.b64decode(j["data_base64"]))["patches"] == scene["patches"]


def test_openapi_embeds_the_nurbs_schema():
    embedded = dict(SCHEMA["components"]["schemas"]["NurbsScene"])
    standalone = {k: v for k, v in NURBS_SCHEMA.items() if k not in ("$schema", "$id")}
    embedded.pop("description")
    standalone.pop("description")
    assert embedded == standalone


def test_nurbs_schema_rejects_what_it_should():
    base = {"format": "nurbsrt-nurbs-scene", "version": 1,
            "source": {"name": "x", "format": "STEP", "declared_units": "mm"}, "units": "mm",
            "bbox": None, "patches": 0, "bodies": [], "faces": [], "warnings": []}
    v = jsonschema.Draft202012Validator(NURBS_SCHEMA)
    v.validate(base)
    assert not v.is_valid({**base, "units": "inch"})
    assert not v.is_valid({**base, "extra": 1})
    assert not v.is_valid({**base, "bbox": {"min": [0, 0], "max": [1, 1, 1]}})


def test_conversion_errors(url):
    check_problem(post_raw(url, "/v1/conversions", SCREW.read_bytes()), 400, "invalid_argument")  # no format
    check_problem(post_raw(url, "/v1/conversions", SCREW.read_bytes(), params={"format": "dwg"}), 400)
    check_problem(post_raw(url, "/v1/conversions", SCREW.read_bytes(), params={"format": "gltf"}), 400)
    check_problem(post_raw(url, "/v1/conversions", b"hello", params={"format": "stl"}), 415)
    check_problem(post_raw(url, "/v1/conversions", b"hello", params={"format": "step"}), 415)
    check_problem(post_raw(url, "/v1/conversions", SCREW.read_bytes()[:1500], params={"format": "iges"}), 422)
    check_problem(post_raw(url, "/v1/conversions", SCREW.read_bytes()[:1500], params={"format": "glb"}), 422)


def test_format_as_form_field_and_download_named_after_the_upload(url):
    files = {"file": ("parts/My Bearing (v2).iges", BEARING.read_bytes()), "format": (None, "step")}
    r = requests.post(url + "/v1/conversions", files=files, timeout=TIMEOUT)
    assert r.status_code == 200, r.text[:300]
    assert r.headers["Content-Type"] == "model/step"
    assert r.headers["Content-Disposition"] == "attachment; filename=\"MyBearingv2.stp\"; filename*=UTF-8''MyBearingv2.stp"
    assert r.content.startswith(b"ISO-10303-21;")
    # The format in two places is refused, not resolved one way.
    check_problem(requests.post(url + "/v1/conversions", files=files, params={"format": "iges"}, timeout=TIMEOUT),
                  400, "invalid_argument")
    two = {**files, "options": (None, '{"format": "stl"}')}
    check_problem(requests.post(url + "/v1/conversions", files=two, timeout=TIMEOUT), 400, "invalid_argument")
    # A name with nothing usable left falls back to "converted".
    r = requests.post(url + "/v1/conversions", files={"file": ("(((.step", SCREW.read_bytes()),
                                                      "format": (None, "iges")}, timeout=TIMEOUT)
    assert r.headers["Content-Disposition"] == "attachment; filename=\"converted.igs\"; filename*=UTF-8''converted.igs"


def test_units_of_the_source_are_kept_or_the_ones_asked_written(url):
    # An IGES file in inches, made by asking for them: the screw is in mm.
    r = post_raw(url, "/v1/conversions", SCREW.read_bytes(), params={"format": "iges", "units": "inch"})
    assert r.status_code == 200, r.text[:300]
    assert b",4HINCH," in r.content[:800]  # the global section's unit name (IGES 5.3 parameter 15)
    # IGES in inches -> STEP: inches, said in the answer, without asking.
    r = requests.post(url + "/v1/conversions", files={"file": ("inch.igs", r.content), "format": (None, "step")},
                      headers={"Accept": "application/json"}, timeout=TIMEOUT)
    assert r.status_code == 200, r.text[:300]
    body = r.json()
    validate(body, "ConversionResponse")
    assert (body["input_units"], body["output_units"]) == ("inch", "inch"), body
    assert b"CONVERSION_BASED_UNIT('INCH'" in base64.b64decode(body["data_base64"])
    # Asked for cm through the options part: written in cm.
    r = requests.post(url + "/v1/conversions",
                      files={"file": ("s.step", SCREW.read_bytes()),
                             "options": (None, '{"format": "step", "units": "cm"}', "application/json")},
                      headers={"Accept": "application/json"}, timeout=TIMEOUT)
    assert r.status_code == 200, r.text[:300]
    assert r.json()["output_units"] == "cm"
    assert b"SI_UNIT(.CENTI.,.METRE.)" in base64.b64decode(r.json()["data_base64"])
    # Unknown units, and units for a format with its own, are refused naming the option.
    for params in ({"format": "step", "units": "furlong"}, {"format": "stl", "units": "inch"}):
        detail = check_problem(post_raw(url, "/v1/conversions", SCREW.read_bytes(), params=params),
                               400, "invalid_argument")["detail"]
        assert "'units'" in detail, detail


def test_mesh_outputs_leave_out_triangles_of_no_area(url):
    r = requests.post(url + "/v1/conversions", files={"file": ("b.iges", BEARING.read_bytes()), "format": (None, "stl")},
                      headers={"Accept": "application/json"}, timeout=TIMEOUT)
    assert r.status_code == 200, r.text[:300]
    body = r.json()
    validate(body, "ConversionResponse")
    tris = parse_stl(base64.b64decode(body["data_base64"]))
    assert len(tris) == body["triangles"]
    for t in tris:
        a, b, c = t[3:6], t[6:9], t[9:12]
        ab = [b[i] - a[i] for i in range(3)]
        ac = [c[i] - a[i] for i in range(3)]
        cross = (ab[1] * ac[2] - ab[2] * ac[1], ab[2] * ac[0] - ab[0] * ac[2], ab[0] * ac[1] - ab[1] * ac[0])
        assert any(x != 0.0 for x in cross), t
    assert body["degenerate_triangles"] > 0  # 16 on bearing.iges (BRepMesh of OCCT 7.6.3)
    assert body["output_units"] == "mm"


def test_brep_and_vrml_outputs_and_a_brep_input(url):
    r = post_raw(url, "/v1/conversions", SCREW.read_bytes(), params={"format": "brep"})
    assert r.status_code == 200, r.text[:300]
    assert r.headers["Content-Type"] == "application/octet-stream"
    assert "converted.brep" in r.headers["Content-Disposition"]
    assert b"CASCADE Topology V" in r.content[:200]
    brep = r.content
    # BREP in: converted, rendered and stored like STEP and IGES.
    r = requests.post(url + "/v1/conversions", files={"file": ("s.brep", brep), "format": (None, "vrml")},
                      headers={"Accept": "application/json"}, timeout=TIMEOUT)
    assert r.status_code == 200, r.text[:300]
    body = r.json()
    validate(body, "ConversionResponse")
    assert (body["input_format"], body["output_format"], body["content_type"]) == ("BREP", "VRML", "model/vrml")
    assert base64.b64decode(body["data_base64"]).startswith(b"#VRML V2.0 utf8")
    assert body["faces"] == 10 and body["triangles"] > 0
    r = post_raw(url, "/v1/renders", brep, params={"width": 48, "height": 48})
    assert r.status_code == 200 and r.headers["Content-Type"] == "image/png", r.text[:300]


def test_fidelity_report_and_strict(url):
    r = requests.post(url + "/v1/conversions", files={"file": ("s.step", SCREW.read_bytes()), "format": (None, "iges")},
                      headers={"Accept": "application/json"}, timeout=TIMEOUT)
    assert r.status_code == 200, r.text[:300]
    body = r.json()
    validate(body, "ConversionResponse")
    f = body["fidelity"]
    assert f["source"]["geometry"]["faces"] == f["output"]["geometry"]["faces"] == 10
    assert f["source"]["geometry"]["solids"] == f["output"]["geometry"]["solids"] == 1
    d = f["relative_differences"]
    assert max(d["volume"], d["area"], d["box"]) < d["tolerance"] == 1e-6, d
    # A mesh output is measured against the exact faces.
    r = requests.post(url + "/v1/conversions", files={"file": ("s.step", SCREW.read_bytes()), "format": (None, "stl")},
                      headers={"Accept": "application/json"}, timeout=TIMEOUT)
    mesh = r.json()["fidelity"]
    assert mesh["output"]["mesh_in_mm"]["triangles"] == r.json()["triangles"]
    assert 0 < mesh["relative_differences"]["area"] < 0.01
    dev = mesh["output"]["deviation_in_mm"]
    assert dev["points"] > r.json()["triangles"] and 0 < dev["mean"] <= dev["p99"] <= dev["max"], dev
    # strict: nothing but the problem when something changed; the file when nothing did.
    detail = check_problem(post_raw(url, "/v1/conversions", SCREW.read_bytes(),
                                    params={"format": "iges", "iges_mode": "faces", "strict": "true"}),
                           422, "strict_refused")["detail"]
    assert "the output holds 0 solid(s), the source 1" in detail, detail
    r = post_raw(url, "/v1/conversions", SCREW.read_bytes(), params={"format": "step", "strict": "true"})
    assert r.status_code == 200 and r.content.startswith(b"ISO-10303-21;"), r.text[:300]


def test_step_schema_and_iges_mode(url):
    r = post_raw(url, "/v1/conversions", SCREW.read_bytes(), params={"format": "step", "step_schema": "ap242"})
    assert r.status_code == 200, r.text[:300]
    assert b"AP242_MANAGED_MODEL_BASED_3D_ENGINEERING" in r.content[:2000]
    r = requests.post(url + "/v1/conversions", files={"file": ("s.step", SCREW.read_bytes()),
                                                      "options": (None, '{"format": "iges", "iges_mode": "faces"}',
                                                                  "application/json")}, timeout=TIMEOUT)
    assert r.status_code == 200, r.text[:300]
    lines = r.content.decode("ascii").splitlines()
    de = [ln for ln in lines if len(ln) >= 73 and ln[72] == "D"]
    types = {int(ln[:8]) for ln in de[::2]}
    assert 144 in types and 186 not in types, sorted(types)
    # An option the format does not take, or a value it does not know, is refused naming it.
    for params, name in (({"format": "iges", "step_schema": "ap242"}, "step_schema"),
                         ({"format": "step", "iges_mode": "faces"}, "iges_mode"),
                         ({"format": "step", "step_schema": "ap203"}, "step_schema")):
        detail = check_problem(post_raw(url, "/v1/conversions", SCREW.read_bytes(), params=params),
                               400, "invalid_argument")["detail"]
        assert f"'{name}'" in detail, detail


def test_coarse_mesh_is_a_warning_strict_refuses(url):
    """deflection asks for a mesh; what it achieved past the fidelity thresholds is a
    warning (header and JSON), which strict refuses. A free-form face meshed at 0.1 of
    the diagonal lies 0.02 of the diagonal from its mesh (the threshold is 0.01)."""
    data = generated_fixture("freeform_bspline").read_bytes()
    r = post_raw(url, "/v1/conversions", data, params={"format": "stl", "deflection": "0.1"})
    assert r.status_code == 200, r.text[:300]
    count, _, listed = r.headers["X-Nurbsrt-Warnings"].partition("; ")
    assert int(count) >= 1 and "the STL mesh lies up to" in listed, r.headers["X-Nurbsrt-Warnings"]
    j = requests.post(url + "/v1/conversions", data=data, params={"format": "stl", "deflection": "0.1"},
                      headers={"Content-Type": "application/octet-stream", "Accept": "application/json"},
                      timeout=TIMEOUT).json()
    validate(j, "ConversionResponse")
    assert any("the STL mesh lies up to" in w for w in j["warnings"]), j["warnings"]
    assert j["fidelity"]["output"]["deviation_in_mm"]["relative_to_diagonal"]["max"] > 0.01
    detail = check_problem(post_raw(url, "/v1/conversions", data,
                                    params={"format": "stl", "deflection": "0.1", "strict": "true"}),
                           422, "strict_refused")["detail"]
    assert "the STL mesh lies up to" in detail, detail
    # The default deflection loses nothing here: no warning, strict answers the file.
    r = post_raw(url, "/v1/conversions", data, params={"format": "stl", "strict": "true"})
    assert r.status_code == 200 and "X-Nurbsrt-Warnings" not in r.headers, r.text[:300]
    # deflection is a mesh option, in (0, 0.1].
    for params, what in (({"format": "step", "deflection": "0.01"}, "applies to STL, GLB, VRML and OBJ outputs only"),
                         ({"format": "stl", "deflection": "0.5"}, "must be a number in (0, ")):
        detail = check_problem(post_raw(url, "/v1/conversions", data, params=params), 400)["detail"]
        assert what in detail, detail


def test_obj_is_answered_as_a_zip_of_obj_and_mtl(url):
    """OBJ writes two files: the answer is a ZIP of <name>.obj and <name>.mtl, the .obj's
    mtllib naming the .mtl, its groups the assembly's parts; JSON wraps the same ZIP."""
    import io
    import zipfile
    data = generated_fixture("assembly").read_bytes()
    r = requests.post(url + "/v1/conversions", files={"file": ("two brackets.step", data), "format": (None, "obj")},
                      timeout=TIMEOUT)
    assert r.status_code == 200, r.text[:300]
    assert r.headers["Content-Type"] == "application/zip"
    assert 'filename="twobrackets.zip"' in r.headers["Content-Disposition"], r.headers["Content-Disposition"]
    z = zipfile.ZipFile(io.BytesIO(r.content))
    assert z.namelist() == ["twobrackets.obj", "twobrackets.mtl"]
    obj = z.read("twobrackets.obj").decode()
    assert "mtllib twobrackets.mtl" in obj
    assert obj.count("\ng two_brackets/bracket\n") == 2, obj[:400]
    assert "newmtl " in z.read("twobrackets.mtl").decode()
    j = requests.post(url + "/v1/conversions", data=data, params={"format": "obj"},
                      headers={"Content-Type": "application/octet-stream", "Accept": "application/json"},
                      timeout=TIMEOUT).json()
    validate(j, "ConversionResponse")
    assert j["content_type"] == "application/zip" and j["output_format"] == "OBJ" and j["output_units"] == "mm"
    assert zipfile.ZipFile(io.BytesIO(base64.b64decode(j["data_base64"]))).namelist() == ["converted.obj", "converted.mtl"]
    assert j["fidelity"]["output"]["deviation_in_mm"]["face_instances"] == 14
    assert j["triangles"] > 0 and j["warnings"] == []
