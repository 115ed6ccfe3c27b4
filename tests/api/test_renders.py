"""POST /v1/renders: real files, raw and multipart, every output format, JSON
variant with statistics, Server-Timing, and the scene cache."""
import base64
import json
import os
import struct
import time

import pytest
import requests

from conftest import BEARING, MODELS, OCCT_DATA, SCREW, TIMEOUT, check_problem, post_raw, server_timing, server_timing_metrics, validate

STAGES = ["read", "nurbs_convert", "mesh", "preliminary_map", "newton", "shade", "encode", "total"]
MAGIC = {"png": b"\x89PNG\r\n\x1a\n", "jpeg": b"\xff\xd8\xff", "exr": b"\x76\x2f\x31\x01"}
CONTENT_TYPE = {"png": "image/png", "jpeg": "image/jpeg", "tiff": "image/tiff", "exr": "image/x-exr"}


def check_image(data, fmt, width=None, height=None):
    if fmt == "tiff":
        assert data[:4] in (b"II*\x00", b"MM\x00*")
    else:
        assert data.startswith(MAGIC[fmt]), data[:8]
    if fmt == "png" and width:
        w, h = struct.unpack(">II", data[16:24])
        assert (w, h) == (width, height)


def check_stats(stats, width, height, wall_ms):
    validate(stats, "Statistics")
    assert (stats["width"], stats["height"]) == (width, height)
    t = stats["timings_ms"]
    assert set(STAGES) <= set(t)
    assert all(v >= 0 for v in t.values())
    render_stages = t["preliminary_map"] + t["newton"] + t["shade"] + t["encode"]
    assert t["total"] >= render_stages * 0.99
    assert t["total"] <= wall_ms * 1.05 + 5  # the server cannot take longer than the client waited
    assert stats["faces"] > 0 and stats["pixels_hit"] > 0


def sample_files():
    files = [SCREW, BEARING, OCCT_DATA / "step" / "linkrods.step", OCCT_DATA / "iges" / "hammer.iges"]
    if MODELS.is_dir():  # small real files of ../shared/models (large ones take tens of seconds)
        for sub in ("step", "iges", "duck"):
            d = MODELS / sub
            small = sorted(p for p in d.iterdir() if p.suffix.lower() in (".stp", ".step", ".igs", ".iges")
                           and p.stat().st_size < 300_000)
            files += small[:4]
    return files


def test_models_present_or_skipped_visibly():
    if not MODELS.is_dir():
        pytest.skip(f"{MODELS} is absent: only /usr/share/opencascade/data files are rendered")


@pytest.mark.parametrize("path", sample_files(), ids=lambda p: p.name)
def test_render_raw_png(url, path):
    t0 = time.monotonic()
    r = post_raw(url, "/v1/renders", path.read_bytes(), params={"width": 96, "height": 72})
    wall_ms = (time.monotonic() - t0) * 1000
    assert r.status_code == 200, r.text[:300]
    assert r.headers["Content-Type"] == "image/png"
    assert r.headers["X-Request-Id"]
    check_image(r.content, "png", 96, 72)
    timing = server_timing(r)
    assert set(STAGES) <= set(timing)
    assert 0 < timing["total"] <= wall_ms * 1.05 + 5


@pytest.mark.parametrize("fmt", ["png", "jpeg", "tiff", "exr"])
def test_render_each_format_multipart(url, fmt):
    opts = {"width": 80, "height": 60, "format": fmt, "view": "front", "method": "martin"}
    r = requests.post(url + "/v1/renders", files={"file": ("part.step", SCREW.read_bytes()),
                                                  "options": (None, json.dumps(opts), "application/json")},
                      timeout=TIMEOUT)
    assert r.status_code == 200, r.text[:300]
    assert r.headers["Content-Type"] == CONTENT_TYPE[fmt]
    check_image(r.content, fmt, 80, 60)


@pytest.mark.parametrize("fmt", ["png", "exr"])
def test_render_json_variant(url, fmt):
    t0 = time.monotonic()
    r = post_raw(url, "/v1/renders", BEARING.read_bytes(),
                 params={"width": 120, "height": 90, "format": fmt, "map_precision": "rgb8"},
                 headers={"Accept": "application/json"})
    wall_ms = (time.monotonic() - t0) * 1000
    assert r.status_code == 200, r.text[:300]
    assert r.headers["Content-Type"].startswith("application/json")
    body = r.json()
    validate(body, "RenderResponse")
    assert body["request_id"] == r.headers["X-Request-Id"]
    assert body["content_type"] == CONTENT_TYPE[fmt]
    check_image(base64.b64decode(body["image_base64"]), fmt, 120, 90)
    check_stats(body["statistics"], 120, 90, wall_ms)
    assert body["statistics"]["map_precision"] == "rgb8"
    assert body["statistics"]["method"] == "proposed"


def test_explicit_camera_in_json_options(url):
    opts = {"width": 64, "height": 64,
            "camera": {"eye": [200, -300, 150], "target": [0, 0, 0], "up": [0, 0, 1], "fov_deg": 30}}
    r = requests.post(url + "/v1/renders", files={"file": ("x", SCREW.read_bytes()), "options": (None, json.dumps(opts))},
                      headers={"Accept": "application/json"}, timeout=TIMEOUT)
    assert r.status_code == 200, r.text[:300]
    cam = r.json()["statistics"]["camera"]
    assert cam["eye"] == [200, -300, 150] and cam["fov_deg"] == 30
    assert "ortho_height" not in cam  # a size that does not apply to the camera is not reported
    r = post_raw(url, "/v1/renders", SCREW.read_bytes(), params={"width": 64, "height": 64, "view": "top",
                                                                 "projection": "orthographic"},
                 headers={"Accept": "application/json"})
    cam = r.json()["statistics"]["camera"]
    assert cam["projection"] == "orthographic" and cam["ortho_height"] > 0 and "fov_deg" not in cam


def test_second_render_of_same_bytes_uses_the_cache(url):
    # Unique bytes (a trailing newline count no other test uses) make the first render a miss.
    data = SCREW.read_bytes() + b"\n" * (7 + os.getpid() % 50)
    first = post_raw(url, "/v1/renders", data, params={"width": 64, "height": 48}, headers={"Accept": "application/json"})
    second = post_raw(url, "/v1/renders", data, params={"width": 64, "height": 48}, headers={"Accept": "application/json"})
    assert first.status_code == 200 and second.status_code == 200
    s1, s2 = first.json()["statistics"], second.json()["statistics"]
    assert s1["cache"] == "miss" and s2["cache"] == "hit"
    assert s1["timings_ms"]["read"] > 0
    for stage in ("read", "nurbs_convert", "mesh"):
        assert s2["timings_ms"][stage] == 0
    assert s2["timings_ms"]["total"] < s1["timings_ms"]["total"]
    assert server_timing_metrics(second)["cache"]["desc"] == "hit"
    assert server_timing_metrics(second)["cache"]["dur"] >= 0  # one metric with both
    m = requests.get(url + "/metrics", timeout=TIMEOUT).text
    assert 'nurbsrt_scene_cache_requests_total{result="hit"}' in m


def test_simultaneous_first_renders_import_once(url):
    # Two workers take both requests at once; the scene cache lets one import the
    # file while the other waits for that import instead of starting its own.
    import concurrent.futures
    data = BEARING.read_bytes() + b"\n" * (60 + os.getpid() % 50)

    def one(_):
        return post_raw(url, "/v1/renders", data, params={"width": 64, "height": 48},
                        headers={"Accept": "application/json"})

    with concurrent.futures.ThreadPoolExecutor(2) as pool:
        results = list(pool.map(one, range(2)))
    assert all(r.status_code == 200 for r in results), [r.text[:200] for r in results]
    caches = sorted(r.json()["statistics"]["cache"] for r in results)
    assert caches == ["hit", "miss"], caches
    reads = sorted(r.json()["statistics"]["timings_ms"]["read"] for r in results)
    assert reads[0] == 0 and reads[1] > 0


# ---- background, alpha and default size (the same rules as the CLI) --------------------------------------

def corner_pixel(png):
    from test_jobs import png_pixels
    width, height, ch, rows = png_pixels(png)
    return (width, height), tuple(rows[0][:ch])


def test_background_alpha_and_defaults(url):
    step = SCREW.read_bytes()

    def corner(**params):
        r = post_raw(url, "/v1/renders", step, params={"width": 64, "height": 48, **params})
        assert r.status_code == 200, r.text[:300]
        return corner_pixel(r.content)[1]

    assert corner() == (0, 0, 0, 0)                            # PNG default: transparent
    assert corner(background="transparent") == (0, 0, 0, 0)
    assert corner(background="1,1,1") == (255, 255, 255, 255)  # a colour alone is opaque
    assert corner(background="0,0,1,0.5") == (0, 0, 255, 128)
    for bad in ("2,0,0", "1,1", "white", "0,0,0,1.5"):
        body = check_problem(post_raw(url, "/v1/renders", step, params={"background": bad}), 400, "invalid_argument")
        assert "background" in body["detail"], body
    files = {"file": ("s.step", step), "options": (None, json.dumps({"width": 40, "height": 30,
                                                                     "background": [0, 1, 0]}))}
    r = requests.post(url + "/v1/renders", files=files, timeout=TIMEOUT)
    assert r.status_code == 200 and corner_pixel(r.content)[1] == (0, 255, 0, 255)


def test_one_side_keeps_the_default_aspect(url):
    step = SCREW.read_bytes()
    for params, size in (({"width": 640}, (640, 480)), ({"height": 300}, (400, 300)), ({}, (800, 600)),
                         ({"width": 50, "height": 70}, (50, 70))):
        r = post_raw(url, "/v1/renders", step, params=params)
        assert r.status_code == 200, r.text[:300]
        assert corner_pixel(r.content)[0] == size, params


# ---- anti-aliasing and feature lines (the same options and checks as the CLI) ------------------------------

def render_png(url, data, **params):
    from test_jobs import png_pixels
    r = post_raw(url, "/v1/renders", data, params={"width": 160, "height": 120, **params},
                 headers={"Accept": "application/json"})
    assert r.status_code == 200, r.text[:300]
    body = r.json()
    validate(body["statistics"], "Statistics")
    width, height, ch, rows = png_pixels(base64.b64decode(body["image_base64"]))
    return body["statistics"], [row[i:i + ch] for row in rows for i in range(0, width * ch, ch)]


def test_antialias_default_on_for_png_and_only_on_edge_pixels(url):
    step = SCREW.read_bytes()
    stats_on, on = render_png(url, step)  # PNG: on by default
    stats_off, off = render_png(url, step, antialias=0)
    assert stats_on["antialias"]["rays_per_edge_pixel"] == 4
    assert stats_off["antialias"] == {"rays_per_edge_pixel": 0, "pixels": 0, "rays": 0}
    edge_pixels = stats_on["antialias"]["pixels"]
    assert 0 < edge_pixels < stats_on["pixels_hit"]
    # Samples off every edge (between four equal centres) are interpolated, not traced.
    assert 0 < stats_on["antialias"]["rays"] <= 4 * edge_pixels
    assert "antialias" in stats_on["timings_ms"]
    changed = sum(a != b for a, b in zip(on, off))
    # Only edge pixels change, and most of them do (partly covered, blended).
    assert 0 < changed <= edge_pixels
    # Partial coverage on a transparent background: alpha strictly between 0 and 255.
    assert sum(0 < p[3] < 255 for p in on) > 20
    assert all(p[3] in (0, 255) for p in off)
    # More rays: same edge pixels, 8 rays each.
    stats8, _ = render_png(url, step, antialias=8)
    assert stats8["antialias"]["pixels"] == edge_pixels
    assert stats_on["antialias"]["rays"] < stats8["antialias"]["rays"] <= 8 * edge_pixels


def test_antialias_off_by_default_for_exr_and_tiff(url):
    step = SCREW.read_bytes()
    for fmt in ("exr", "tiff"):
        r = post_raw(url, "/v1/renders", step, params={"width": 64, "height": 48, "format": fmt},
                     headers={"Accept": "application/json"})
        assert r.status_code == 200, r.text[:300]
        assert r.json()["statistics"]["antialias"]["rays_per_edge_pixel"] == 0, fmt


def test_edges_drawn_over_the_shading(url):
    step = SCREW.read_bytes()
    stats_plain, plain = render_png(url, step, antialias=0, background="1,1,1")
    stats_lines, lines = render_png(url, step, antialias=0, background="1,1,1", edges="true",
                                    edge_color="1,0,0", edge_width=2)
    assert "edges" in stats_lines["timings_ms"]
    red = sum(p[0] > 240 and p[1] < 15 and p[2] < 15 for p in lines)
    assert sum(p[0] > 240 and p[1] < 15 and p[2] < 15 for p in plain) == 0
    assert red > 100, red  # the silhouette and the face borders of the screw, 2 px wide
    files = {"file": ("s.step", step), "options": (None, json.dumps(
        {"width": 160, "height": 120, "antialias": 0, "background": [1, 1, 1], "edges": True,
         "edge_color": [1, 0, 0], "edge_width": 2}))}
    r = requests.post(url + "/v1/renders", files=files, timeout=TIMEOUT)
    from test_jobs import png_pixels
    width, _, ch, rows = png_pixels(r.content)
    as_json = [row[i:i + ch] for row in rows for i in range(0, width * ch, ch)]
    assert as_json == lines  # the JSON options and the query parameters mean the same


def test_shadows_darken_only_shadowed_pixels(url):
    """Exact shadows of the key light: the linkrods cast shadows on each other;
    shadowed pixels only darken, hits and coverage stay, and the statistics say
    what the light's map and rays cost."""
    step = (OCCT_DATA / "step" / "linkrods.step").read_bytes()
    stats_plain, plain = render_png(url, step, antialias=0)
    stats_shadow, shadowed = render_png(url, step, antialias=0, shadows="true")
    assert stats_plain["shadows"] == {"enabled": False, "map_size": 0, "rays": 0, "shadowed_pixels": 0,
                                      "ground": False, "ground_shadowed_pixels": 0}
    sh = stats_shadow["shadows"]
    assert sh["enabled"] and sh["map_size"] >= 256 and sh["rays"] > 0 and sh["shadowed_pixels"] > 0, sh
    assert stats_shadow["timings_ms"]["shadow_map"] > 0
    assert stats_plain["pixels_hit"] == stats_shadow["pixels_hit"]
    darker = sum(1 for a, b in zip(plain, shadowed) if a != b)
    assert all(b[3] == a[3] for a, b in zip(plain, shadowed))
    assert all(sum(b[:3]) <= sum(a[:3]) for a, b in zip(plain, shadowed))
    assert 0 < darker <= sh["shadowed_pixels"] + 2, (darker, sh)  # sRGB rounding may hide a few


def test_ground_takes_the_shadow(url):
    """A ground under the part: over a transparent background only its shadow
    shows (black, alpha 0.5), over an opaque one a lit floor covers the
    background; both cast the same exact shadow, and the AOVs keep it background."""
    step = (OCCT_DATA / "step" / "linkrods.step").read_bytes()
    stats_plain, plain = render_png(url, step, antialias=0)
    stats, catcher = render_png(url, step, antialias=0, ground="true")
    sh = stats["shadows"]
    assert sh["enabled"] and sh["ground"] and sh["ground_shadowed_pixels"] > 100, sh
    assert stats["pixels_hit"] == stats_plain["pixels_hit"]
    shadow = [p for p in catcher if p[3] in (127, 128) and p[:3] == b"\0\0\0"]
    assert len(shadow) == sh["ground_shadowed_pixels"]
    assert all(p[3] in (0, 127, 128, 255) for p in catcher)
    stats_floor, floor = render_png(url, step, antialias=0, ground="true", background="1,1,1")
    assert stats_floor["shadows"]["ground_shadowed_pixels"] == sh["ground_shadowed_pixels"]
    assert all(p[3] == 255 for p in floor)
    assert sum(p[:3] == b"\xff\xff\xff" for p in floor) < 0.01 * len(floor)  # the floor hides the background


@pytest.mark.parametrize("params,field", [
    ({"antialias": -1}, "antialias"), ({"antialias": 65}, "antialias"), ({"antialias": 2.5}, "antialias"),
    ({"antialias": "many"}, "antialias"), ({"edges": "yes"}, "edges"), ({"edge_width": 0}, "edge_width"),
    ({"edge_width": 100}, "edge_width"), ({"edge_color": "1,0"}, "edge_color"), ({"edge_color": "2,0,0"}, "edge_color"),
    ({"shadows": "maybe"}, "shadows"), ({"ground": "yes"}, "ground"), ({"ground_height": "low"}, "ground_height"),
])
def test_bad_antialias_and_edge_options(url, params, field):
    body = check_problem(post_raw(url, "/v1/renders", SCREW.read_bytes(), params=params), 400, "invalid_argument")
    assert field in body["detail"], body


# A plane through the screw's bounding-box centre, its normal (+x) towards the
# iso view's eye: the near half is removed and the cut faces the camera.
SCREW_SECTION = "-17.9,-0.84,-13.4,1,0,0"


def test_section_plane_cuts_and_caps(url):
    """A section plane removes its half exactly, closed bodies show caps (the
    statistics count them, the face AOV marks them above 2^31), without caps the
    inside shows; the JSON form means what the query form means."""
    step = SCREW.read_bytes()
    stats_plain, plain = render_png(url, step, antialias=0)
    stats_cut, cut = render_png(url, step, antialias=0, sections=SCREW_SECTION)
    stats_open, opened = render_png(url, step, antialias=0, sections=SCREW_SECTION, section_caps="false")
    assert stats_plain["sections"] == {"planes": 0, "cap_pixels": 0, "open_bodies_cut": 0}
    assert stats_cut["sections"]["planes"] == 1 and stats_cut["sections"]["cap_pixels"] > 500, stats_cut["sections"]
    assert stats_open["sections"]["cap_pixels"] == 0
    assert cut != plain and opened != cut
    r = post_raw(url, "/v1/renders", step, params={"width": 160, "height": 120, "antialias": 0,
                                                   "sections": SCREW_SECTION, "aovs": "face"},
                 headers={"Accept": "application/json"})
    assert r.status_code == 200, r.text[:300]
    timing = server_timing(r)  # the cached scene, cut again: no import, no prepare
    assert timing["read"] == 0 and timing["prepare"] == 0, timing
    faces = struct.unpack("<%dI" % (160 * 120), base64.b64decode(r.json()["aovs"]["face"]["data"]))
    assert sum(f >= 2 ** 31 for f in faces) == stats_cut["sections"]["cap_pixels"]
    files = {"file": ("s.step", step), "options": (None, json.dumps(
        {"width": 160, "height": 120, "antialias": 0,
         "sections": [{"point": [-17.9, -0.84, -13.4], "normal": [2, 0, 0]}]}))}
    r = requests.post(url + "/v1/renders", files=files, timeout=TIMEOUT)
    from test_jobs import png_pixels
    width, _, ch, rows = png_pixels(r.content)
    assert [row[i:i + ch] for row in rows for i in range(0, width * ch, ch)] == cut


@pytest.mark.parametrize("params,field", [
    ({"sections": "0,0,0,0,0,0"}, "normal"), ({"sections": "0,0,0,1,0"}, "sections"),
    ({"sections": ";".join(["0,0,0,1,0,0"] * 7)}, "sections"), ({"sections": "0,0,0,nan,0,1"}, "sections"),
    ({"section_mode": "half"}, "section_mode"), ({"section_caps": "maybe"}, "section_caps"),
])
def test_bad_section_options(url, params, field):
    body = check_problem(post_raw(url, "/v1/renders", SCREW.read_bytes(), params=params), 400, "invalid_argument")
    assert field in body["detail"], body


def test_bad_section_planes_in_json(url):
    for planes, field in [([{"point": [0, 0, 0], "normal": [0, 0, 0]}], "normal"),
                          ([{"point": [0, 0, 0], "normal": [0, 0, 1], "side": 1}], "side"),
                          ([{"point": [0, 0, 0]}], "sections[0]"),
                          ([{"point": [0, 0, 0], "normal": [0, 0, 1]}] * 7, "sections")]:
        files = {"file": ("s.step", SCREW.read_bytes()), "options": (None, json.dumps({"sections": planes}))}
        body = check_problem(requests.post(url + "/v1/renders", files=files, timeout=TIMEOUT), 400, "invalid_argument")
        assert field in body["detail"], body


def test_parts_hidden_isolated_and_recoloured(url):
    """Parts by id or name glob: hidden ones leave the frame, `only` isolates,
    colours replace the file's; the cached scene re-renders any selection
    without an import or a prepare (Server-Timing)."""
    as1 = MODELS / "step" / "as1-oc-214.stp"
    if not as1.exists():
        pytest.skip("../shared/models is absent: the assembly as1 is not there")
    data = as1.read_bytes()
    stats_all, _ = render_png(url, data, antialias=0)
    assert stats_all["parts"] == {"hidden_faces": 0, "recoloured_faces": 0, "moved_faces": 0, "ghost_faces": 0,
                                  "ghost_pixels": 0, "ghost_behind_ms": 0}
    r = post_raw(url, "/v1/renders", data, headers={"Accept": "application/json"}, params={
        "width": 160, "height": 120, "antialias": 0,
        "parts": json.dumps({"hide": ["l-bracket-assembly_*"], "color": {"rod_1": "0,0,1"}})})
    assert r.status_code == 200, r.text[:300]
    stats = r.json()["statistics"]
    assert (stats["parts"]["hidden_faces"], stats["parts"]["recoloured_faces"]) == (122, 4), stats["parts"]
    timing = server_timing(r)
    assert timing.get("import", 0) == 0 and timing["read"] == 0 and timing["prepare"] == 0, timing
    stats_only, _ = render_png(url, data, antialias=0, parts=json.dumps({"only": ["0/2"]}))
    assert stats_only["parts"]["hidden_faces"] == 160 - 18
    stats_ghost, ghosted = render_png(url, data, antialias=0, parts=json.dumps({"ghost": ["l-bracket-assembly_1"]}))
    assert stats_ghost["parts"]["ghost_faces"] == 61 and stats_ghost["parts"]["ghost_pixels"] > 0, stats_ghost["parts"]
    assert stats_ghost["parts"]["ghost_behind_ms"] > 0


def test_explode_moves_the_parts_apart(url):
    """An exploded as1: the parts move apart (the view, fitted to them, shows
    them smaller), and the cached scene serves every factor and level without
    an import or a prepare; a factor outside [0, 10] is refused."""
    as1 = MODELS / "step" / "as1-oc-214.stp"
    if not as1.exists():
        pytest.skip("../shared/models is absent: the assembly as1 is not there")
    data = as1.read_bytes()
    stats_plain, _ = render_png(url, data, antialias=0)
    r = post_raw(url, "/v1/renders", data, headers={"Accept": "application/json"},
                 params={"width": 160, "height": 120, "antialias": 0, "explode": 0.3})
    assert r.status_code == 200, r.text[:300]
    timing = server_timing(r)
    assert timing.get("import", 0) == 0 and timing["read"] == 0 and timing["prepare"] == 0, timing
    assert 0 < r.json()["statistics"]["pixels_hit"] < stats_plain["pixels_hit"]
    r2 = post_raw(url, "/v1/renders", data, headers={"Accept": "application/json"},
                  params={"width": 160, "height": 120, "antialias": 0, "explode": 1.5, "explode_level": "leaves"})
    assert r2.status_code == 200, r2.text[:300]
    assert server_timing(r2)["prepare"] == 0, server_timing(r2)
    assert 0 < r2.json()["statistics"]["pixels_hit"] < r.json()["statistics"]["pixels_hit"]
    # An explicit move of one part, in the frame too: no prepare, its faces counted.
    r3 = post_raw(url, "/v1/renders", data, headers={"Accept": "application/json"},
                  params={"width": 160, "height": 120, "antialias": 0,
                          "parts": json.dumps({"move": {"rod_1": [0, 0, 200]}})})
    assert r3.status_code == 200, r3.text[:300]
    assert server_timing(r3)["prepare"] == 0, server_timing(r3)
    assert r3.json()["statistics"]["parts"]["moved_faces"] > 0, r3.json()["statistics"]["parts"]
    body = check_problem(post_raw(url, "/v1/renders", data, params={"parts": json.dumps({"move": {"rod_1": [0, 0]}})}),
                         400, "invalid_argument")
    assert "parts.move" in body["detail"], body
    for bad in (-1, 11, "far"):
        body = check_problem(post_raw(url, "/v1/renders", SCREW.read_bytes(), params={"explode": bad}), 400,
                             "invalid_argument")
        assert "explode" in body["detail"], body


def test_bad_parts_options(url):
    for parts, field in [({"hide": ["gear*"]}, "parts.hide[0] 'gear*' matches no part"),
                         ({"explode": ["a"]}, "explode"), ({"ghost": ["gear*"]}, "parts.ghost[0]"),
                         ({"only": "a"}, "parts.only"),
                         ({"color": {"a": [2, 0, 0]}}, "parts.color")]:
        body = check_problem(post_raw(url, "/v1/renders", SCREW.read_bytes(), params={"parts": json.dumps(parts)}),
                             400, "invalid_argument")
        assert field in body["detail"], body


def test_views_make_a_labelled_contact_sheet(url):
    """Four views of one upload in one image: a 2 x 2 sheet of 160 x 120 cells,
    the statistics of each view, one import."""
    step = SCREW.read_bytes()
    r = post_raw(url, "/v1/renders", step, headers={"Accept": "application/json"},
                 params={"width": 160, "height": 120, "views": "front,top,right,iso", "aovs": "face"})
    assert r.status_code == 200, r.text[:300]
    body = r.json()
    validate(body, "RenderResponse")
    from test_jobs import png_pixels
    width, height, _, _ = png_pixels(base64.b64decode(body["image_base64"]))
    assert (width, height) == (320, 240)
    views = body["statistics"]["views"]
    assert [v["view"] for v in views] == ["front", "top", "right", "iso"]
    assert all(v["statistics"]["pixels_hit"] > 0 and v["camera"]["projection"] == "orthographic" for v in views)
    faces = struct.unpack("<%dI" % (320 * 240), base64.b64decode(body["aovs"]["face"]["data"]))
    for cell in range(4):  # every cell shows the part
        x0, y0 = 160 * (cell % 2), 120 * (cell // 2)
        assert any(faces[(y0 + y) * 320 + x0 + x] for y in range(120) for x in range(160)), cell
    assert server_timing(r)["read"] >= 0 and sum(1 for v in views) == 4


def test_views_of_cameras(url):
    """views may mix named views and cameras of their own: each camera view
    renders as a request with that camera alone; labels name the ZIP's entries;
    a bad camera field is refused naming views[k]."""
    import io
    import zipfile
    step = SCREW.read_bytes()
    cam = {"eye": [60, -80, 50], "target": [0, 0, 0], "fov_deg": 35}
    options = {"width": 128, "height": 96, "antialias": 0, "layout": "separate",
               "views": ["front", dict(cam, name="closeup"), {"view": "top", "projection": "perspective"}]}
    r = requests.post(url + "/v1/renders", files={"file": ("screw.step", step), "options": (None, json.dumps(options))},
                      timeout=TIMEOUT)
    assert r.status_code == 200, r.text[:300]
    archive = zipfile.ZipFile(io.BytesIO(r.content))
    assert archive.namelist() == ["front.png", "closeup.png", "top.png"]
    alone = requests.post(url + "/v1/renders", files={"file": ("screw.step", step), "options": (None, json.dumps(
        {"width": 128, "height": 96, "antialias": 0, "camera": cam}))}, timeout=TIMEOUT)
    assert alone.status_code == 200 and alone.content == archive.read("closeup.png")
    j = requests.post(url + "/v1/renders", headers={"Accept": "application/json"}, files={
        "file": ("screw.step", step), "options": (None, json.dumps(dict(options, layout="sheet")))}, timeout=TIMEOUT)
    assert j.status_code == 200, j.text[:300]
    views = j.json()["statistics"]["views"]
    assert [v["view"] for v in views] == ["front", "closeup", "top"]
    assert [v["camera"]["projection"] for v in views] == ["orthographic", "perspective", "perspective"]
    bad = dict(options, views=["front", {"eye": [1, 2]}])
    body = check_problem(requests.post(url + "/v1/renders", files={
        "file": ("screw.step", step), "options": (None, json.dumps(bad))}, timeout=TIMEOUT), 400, "invalid_argument")
    assert "views[1].eye" in body["detail"], body


def test_views_separate_answer_a_zip_of_images(url):
    """layout separate: a ZIP of one image per view, named after it, each the
    size of one view and the same image as a request for that view alone; in
    JSON a list of images; Accept of an image type alone is 406; one import."""
    import io
    import zipfile
    from test_jobs import png_size
    step = SCREW.read_bytes()
    params = {"width": 160, "height": 120, "views": "front,top,iso", "layout": "separate", "antialias": 0}
    r = post_raw(url, "/v1/renders", step, params=params)
    assert r.status_code == 200, r.text[:300]
    assert r.headers["Content-Type"] == "application/zip"
    archive = zipfile.ZipFile(io.BytesIO(r.content))
    assert archive.testzip() is None
    assert archive.namelist() == ["front.png", "top.png", "iso.png"]
    for name in archive.namelist():
        png = archive.read(name)
        assert png_size(png) == (160, 120), name
    alone = post_raw(url, "/v1/renders", step, params={"width": 160, "height": 120, "view": "top", "antialias": 0})
    assert alone.status_code == 200 and alone.content == archive.read("top.png")
    # The same request again gives the same bytes (fixed entry times).
    assert post_raw(url, "/v1/renders", step, params=params).content == r.content
    j = post_raw(url, "/v1/renders", step, params={**params, "format": "jpeg", "aovs": "face"},
                 headers={"Accept": "application/json"})
    assert j.status_code == 200, j.text[:300]
    body = j.json()
    validate(body, "RenderResponse")
    assert "image_base64" not in body and [i["view"] for i in body["images"]] == ["front", "top", "iso"]
    assert all(base64.b64decode(i["image_base64"])[:3] == b"\xff\xd8\xff" for i in body["images"])
    assert all(len(base64.b64decode(i["aovs"]["face"]["data"])) == 4 * 160 * 120 for i in body["images"])
    check_problem(post_raw(url, "/v1/renders", step, params=params, headers={"Accept": "image/png"}), 406)
    body = check_problem(post_raw(url, "/v1/renders", step, params={"layout": "separate"}), 400, "invalid_argument")
    assert "layout" in body["detail"], body
    body = check_problem(post_raw(url, "/v1/renders", step, params={**params, "layout": "grid"}), 400,
                         "invalid_argument")
    assert "layout" in body["detail"], body


@pytest.mark.parametrize("params,field", [
    ({"views": ""}, "views"), ({"views": "front,side"}, "side"), ({"views": ",".join(["iso"] * 17)}, "1 to 16"),
])
def test_bad_views(url, params, field):
    body = check_problem(post_raw(url, "/v1/renders", SCREW.read_bytes(), params=params), 400, "invalid_argument")
    assert field in body["detail"], body


def hit_box(png):
    """Bounding box (x0, y0, x1, y1) of the non-transparent pixels, and the image size."""
    from test_jobs import png_pixels
    width, height, ch, rows = png_pixels(png)
    assert ch == 4
    xs, ys = [], []
    for y, row in enumerate(rows):
        hit = [x for x in range(width) if row[4 * x + 3] > 0]
        if hit:
            xs += [hit[0], hit[-1]]
            ys.append(y)
    return (min(xs), min(ys), max(xs), max(ys)), (width, height)


def test_fit_margin_frames_the_part(url):
    """Named views frame the whole part: 5 % of the frame empty on each side by
    default (the part spans 90 % on its binding axis); fit_margin sets it."""
    data = BEARING.read_bytes()

    def fill(**params):
        r = post_raw(url, "/v1/renders", data, params={"width": 160, "height": 120, **params})
        assert r.status_code == 200, r.text[:300]
        (x0, y0, x1, y1), (w, h) = hit_box(r.content)
        assert x0 > 0 and y0 > 0 and x1 < w - 1 and y1 < h - 1, (params, (x0, y0, x1, y1))
        return max((x1 - x0 + 1) / w, (y1 - y0 + 1) / h), min(x0, y0, w - 1 - x1, h - 1 - y1)

    for view in ("front", "iso", "top"):
        for projection in ("perspective", "orthographic"):
            spans, border = fill(view=view, projection=projection)
            assert 0.8 <= spans <= 0.92, (view, projection, spans)
            spans, border = fill(view=view, projection=projection, fit_margin=0.2)
            assert 0.55 <= spans <= 0.62 and border >= 23, (view, projection, spans, border)
    files = {"file": ("b.iges", data),
             "options": (None, json.dumps({"width": 160, "height": 120, "camera": {"view": "left", "fit_margin": 0}}))}
    r = requests.post(url + "/v1/renders", files=files, timeout=TIMEOUT)
    assert r.status_code == 200, r.text[:300]
    for bad in (-0.1, 0.5, "wide"):
        body = check_problem(post_raw(url, "/v1/renders", data, params={"fit_margin": bad}), 400, "invalid_argument")
        assert "fit_margin" in body["detail"], body


def test_eye_alone_looks_at_the_model_centre(url):
    """An eye without a target looks at the middle of the model's box (as
    `nurbsrt info` reports it), and an orthographic height is fitted from there."""
    import subprocess
    info = json.loads(subprocess.run([os.environ["NURBSRT_BIN"], "info", "--json", str(SCREW)],
                                     capture_output=True, check=True, text=True).stdout)
    centre = [(a + b) / 2 for a, b in zip(info["bbox"]["min"], info["bbox"]["max"])]
    for projection in ("perspective", "orthographic"):
        r = post_raw(url, "/v1/renders", SCREW.read_bytes(),
                     params={"width": 80, "height": 60, "eye": "100,-200,50", "projection": projection},
                     headers={"Accept": "application/json"})
        assert r.status_code == 200, r.text[:300]
        cam = r.json()["statistics"]["camera"]
        assert cam["eye"] == [100, -200, 50]
        assert all(abs(t - c) < 1e-6 for t, c in zip(cam["target"], centre)), (cam["target"], centre)
        if projection == "orthographic":
            assert 0 < cam["ortho_height"] < info["bbox"]["diagonal"] / 0.9 + 1e-9, cam


def test_warnings_reach_every_render_answer(url):
    """What the import worked around is on the image answer (X-Nurbsrt-Warnings) and
    the JSON one (header, `warnings`, statistics.warnings) alike; a clean file has none."""
    turbine = MODELS / "step" / "ec_turbine-A.stp"
    if not turbine.is_file():
        pytest.skip(f"{turbine} is absent")
    data = turbine.read_bytes()
    image = post_raw(url, "/v1/renders", data, params={"width": 48, "height": 32})
    assert image.status_code == 200, image.text[:300]
    count, _, listed = image.headers["X-Nurbsrt-Warnings"].partition("; ")
    assert int(count) >= 1 and any(w.startswith("face 2: BRepMesh left part of it") for w in json.loads(listed))
    j = post_raw(url, "/v1/renders", data, params={"width": 48, "height": 32}, headers={"Accept": "application/json"})
    assert j.status_code == 200
    validate(j.json(), "RenderResponse")
    assert j.headers["X-Nurbsrt-Warnings"] == image.headers["X-Nurbsrt-Warnings"]
    assert j.json()["warnings"] == j.json()["statistics"]["warnings"] and len(j.json()["warnings"]) == int(count)
    clean = post_raw(url, "/v1/renders", SCREW.read_bytes(), params={"width": 48}, headers={"Accept": "application/json"})
    assert "X-Nurbsrt-Warnings" not in clean.headers and clean.json()["warnings"] == []
