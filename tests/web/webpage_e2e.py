"""End-to-end test of the web page in a real headless Chromium, driven over the
DevTools protocol, against a running `nurbsrt serve` (NURBSRT_URL). Started by
tests/webpage.sh. Each step checks what a user would see; the first failure
saves a screenshot and the page's console to NURBSRT_WEB_ARTIFACTS and fails.

Usage: webpage_e2e.py STEP_FILE OTHER_CAD_FILE [PART_OF_ABOUT_300_FACES [ASSEMBLY [CUBE_10MM [CYLINDER]]]]"""
import json
import os
import pathlib
import shutil
import statistics
import struct
import subprocess
import sys
import tempfile
import re
import time
import traceback
import urllib.parse
import urllib.request

from cdp import Browser, find_chromium

URL = os.environ["NURBSRT_URL"]
ARTIFACTS = pathlib.Path(os.environ.get("NURBSRT_WEB_ARTIFACTS") or tempfile.mkdtemp(prefix="nurbsrt-web-"))
SCREENSHOT = os.environ.get("NURBSRT_WEB_SCREENSHOT")  # where to save the README picture, if set
KEY = os.environ.get("NURBSRT_WEB_KEY", "")  # the service's API key, typed into the page
MEASURE_SCREENSHOT = os.environ.get("NURBSRT_WEB_MEASURE_SCREENSHOT")  # the README's measuring picture, if set
ONLY = os.environ.get("NURBSRT_WEB_ONLY")  # "measure" or "viewer": the page's load, the upload and those steps only
RENDERS = "/v1/renders"

# Pixels of the canvas: how many differ from the background, a checksum, and
# the number of distinct colours among them (a face-id view has many).
PIXELS_JS = """(() => {
  const c = document.getElementById('view');
  const d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;
  const bg = document.getElementById('background').value.split(',').map(x => Math.round(Number(x) * 255));
  let differ = 0, sum = 0; const colours = new Set();
  for (let i = 0; i < d.length; i += 4) {
    sum = (sum * 31 + d[i] + 7 * d[i + 1] + 13 * d[i + 2]) % 1000000007;
    if (Math.abs(d[i] - bg[0]) > 8 || Math.abs(d[i + 1] - bg[1]) > 8 || Math.abs(d[i + 2] - bg[2]) > 8) {
      differ++;
      if (colours.size < 5000) colours.add((d[i] << 16) | (d[i + 1] << 8) | d[i + 2]);
    }
  }
  return {width: c.width, height: c.height, differ, sum, colours: colours.size};
})()"""


def log(msg):
    print(f"webpage: {msg}", flush=True)


class Page:
    def __init__(self, browser):
        self.b = browser

    def ev(self, js):
        return self.b.evaluate(js)

    def frames(self):
        return int(self.ev("Number(document.getElementById('view').dataset.frames || 0)"))

    def wait_final_after(self, frames_before, timeout=120):
        """Waits for a full-size frame after `frames_before`; fails at once on an error message."""
        state = self.b.wait_for(
            f"(() => {{ const c = document.getElementById('view');"
            f" const m = document.getElementById('messages').textContent;"
            f" if (m) return 'error: ' + m;"
            f" return Number(c.dataset.frames || 0) > {frames_before} && c.dataset.final === '1'"
            f" && c.dataset.busy === '0' ? 'ok' : ''; }})()", timeout, "a full-size frame")
        assert state == "ok", f"the page shows {state}"

    def canvas_centre(self):
        r = self.ev("(() => { const r = document.getElementById('view').getBoundingClientRect();"
                    " return [r.left, r.top, r.width, r.height]; })()")
        return r[0] + r[2] / 2, r[1] + r[3] / 2, r

    def scroll_to(self, element_id):
        self.ev(f"document.getElementById('{element_id}').scrollIntoView({{block: 'center'}})")

    def set_select(self, element_id, value):
        self.ev(f"(() => {{ const s = document.getElementById('{element_id}'); s.value = '{value}';"
                f" s.dispatchEvent(new Event('change', {{bubbles: true}})); }})()")

    def set_files(self, element_id, paths):
        # Absolute paths without '..': Chromium refuses to upload a file named
        # through a parent reference (net::ERR_ACCESS_DENIED).
        oid = self.b.object_id(f"document.getElementById('{element_id}')")
        self.b.call("DOM.setFileInputFiles", files=[str(pathlib.Path(p).resolve()) for p in paths], objectId=oid)


def console_errors(events):
    out = []
    for e in events:
        m, p = e["method"], e.get("params", {})
        if m == "Runtime.consoleAPICalled" and p.get("type") in ("error", "assert"):
            out.append("console: " + " ".join(str(a.get("value", a.get("description", ""))) for a in p.get("args", [])))
        elif m == "Runtime.exceptionThrown":
            out.append("exception: " + json.dumps(p.get("exceptionDetails", {}))[:400])
        elif m == "Log.entryAdded" and p.get("entry", {}).get("level") == "error":
            out.append(f"log: {p['entry'].get('text')} {p['entry'].get('url', '')}")
    return out


def render_requests(events, since):
    """(requests sent, most in flight at once, seconds each completed one took) of
    POST /v1/renders since `since`."""
    live, most, sent, durations = {}, 0, 0, []
    for e in events:
        if e["time"] < since:
            continue
        m, p = e["method"], e.get("params", {})
        if m == "Network.requestWillBeSent" and p["request"]["url"].endswith(RENDERS):
            sent += 1
            live[p["requestId"]] = e["time"]
            most = max(most, len(live))
        elif m in ("Network.loadingFinished", "Network.loadingFailed"):
            start = live.pop(p["requestId"], None)
            if start is not None and m == "Network.loadingFinished":
                durations.append(e["time"] - start)
    return sent, most, durations


def drag(page, dx_total, steps, pause):
    """Drags across the image; returns (release time, mouse moves sent)."""
    x, y, _ = page.canvas_centre()
    page.b.mouse("mousePressed", x, y)
    for i in range(1, steps + 1):
        page.b.mouse("mouseMoved", x + dx_total * i / steps, y + 0.2 * dx_total * i / steps)
        page.b.pump(pause)
    page.b.mouse("mouseReleased", x + dx_total, y + 0.2 * dx_total, buttons=0)
    return time.monotonic(), steps


def step_load(page):
    page.b.call("Page.navigate", url=URL + "/")
    page.b.wait_for("document.body && document.body.dataset.ready === '1'", 30, "the page's modules")
    page.b.pump(0.5)
    errors = console_errors(page.b.events)
    assert not errors, f"console errors on load: {errors}"
    csp = page.ev("fetch('/').then(r => r.headers.get('Content-Security-Policy'))")
    assert csp and "default-src 'self'" in csp and "unsafe-inline" not in csp, f"CSP: {csp}"
    if KEY:  # typed into the key field and submitted with Enter, as a user would
        page.ev("document.getElementById('api-key').focus()")
        page.b.call("Input.insertText", text=KEY)
        page.b.key("Enter", "Enter", 13, text="\r")
        stored = page.ev("sessionStorage.getItem('nurbsrt.apiKey')")
        assert stored == KEY, "the key was not kept in session storage"
        assert page.ev("document.getElementById('api-key').value") == "", "the key stays visible in the field"


def check_key_use(events):
    """Every API request carried the key in its Authorization header and none in its URL."""
    api = [e["params"]["request"] for e in events
           if e["method"] == "Network.requestWillBeSent" and "/v1/" in e["params"]["request"]["url"]]
    assert api, "no API requests seen"
    for r in api:
        assert KEY not in r["url"], f"the key is in a URL: {r['url']}"
        if KEY:
            assert r["headers"].get("Authorization") == f"Bearer {KEY}", f"{r['method']} {r['url']} without the key"
    log(f"API key: sent as a header with all {len(api)} API requests, in no URL")


def step_upload(page, step_file):
    before = page.frames()
    t0 = time.monotonic()
    page.set_files("file", [step_file])
    page.b.wait_for("!document.getElementById('busy').hidden || Number(document.getElementById('view').dataset.frames"
                    f" || 0) > {before}", 10, "the progress indication")
    page.wait_final_after(before)
    px = page.ev(PIXELS_JS)
    log(f"first render {px['width']}x{px['height']} in {time.monotonic() - t0:.2f} s; {px['differ']} pixels not background")
    assert (px["width"], px["height"]) == (800, 600), px
    assert px["differ"] > 0.02 * px["width"] * px["height"], f"the image is (nearly) all background: {px}"
    stages = page.ev("[...document.querySelectorAll('#stages > div')].map(d => d.dataset.stage)")
    # The import ran when the file was stored (POST /v1/files): its first frame finds the scene cached.
    assert "newton" in stages and "preliminary_map" in stages, f"stage bar: {stages}"
    return px


def step_orbit(page, px_before):
    since = time.monotonic()
    before = page.frames()
    # A page that sent one request per move would send 41; this one coalesces
    # them (one in flight, one pending), so it sends about one request per
    # preview that completes during the drag, plus the first and the final.
    released, moves = drag(page, 160, 40, 0)
    drag_s = released - since
    page.wait_final_after(before)
    page.b.pump(0.2)
    sent, most, durations = render_requests(page.b.events, since)
    px = page.ev(PIXELS_JS)
    preview_s = statistics.median(durations) if durations else 0.0
    log(f"orbit: {moves} mouse moves in {drag_s:.2f} s -> {sent} render requests (median "
        f"{1000 * preview_s:.0f} ms each), at most {most} in flight")
    assert px["sum"] != px_before["sum"], "the image did not change after orbiting"
    assert px["differ"] > 0.02 * px["width"] * px["height"], "the orbited image is all background"
    # The coalescing bound follows from the measured speeds (previews faster than
    # the moves arrive need no coalescing, and the bound then exceeds the moves);
    # a page sending per move exceeds it whenever previews are slower than moves.
    bound = min(moves + 1, drag_s / max(preview_s, 1e-3) + 3)
    assert 2 <= sent <= bound, (f"{sent} render requests for one drag of {moves} moves in {drag_s:.2f} s with "
                                f"previews of {1000 * preview_s:.0f} ms (want coalesced previews + a final: "
                                f"at most {bound:.1f})")
    # One in flight; an aborted one may still be reported for a moment beside its successor.
    assert most <= 2, f"{most} render requests in flight at once"
    return px


def step_latency(page, what, repeats=3):
    """Pointer release -> full-size (800x600) frame of the cached part, as the page measures it."""
    samples = []
    for i in range(repeats):
        before = page.frames()
        drag(page, -40 if i % 2 else 40, 4, 0.02)
        page.wait_final_after(before)
        samples.append(float(page.ev("document.getElementById('view').dataset.latencyMs")))
    log(f"interaction latency, {what} (pointer release -> full-size 800x600 frame, cached scene): "
        f"median {statistics.median(samples):.0f} ms, samples {[round(s) for s in samples]} ms")
    return samples


def hover_readout(page):
    """Hovers the centre of the image (on the part): the AOV readout names a face."""
    page.ev("document.getElementById('hover').textContent = ''")
    x, y, _ = page.canvas_centre()
    page.b.mouse("mouseMoved", x + 1, y, buttons=0)
    page.b.mouse("mouseMoved", x, y, buttons=0)
    return page.b.wait_for("(() => { const t = document.getElementById('hover').textContent;"
                           " return t.startsWith('pixel') ? t : ''; })()", 30, "the hover readout")


def step_look_inside(page, px_shaded):
    # The shaded view fetches the AOVs on the first hover.
    hover = hover_readout(page)
    log("hover (shaded view): " + hover.replace("\n", "; "))
    assert "face" in hover and "iterations" in hover, hover
    page.set_select("look", "face")
    page.b.wait_for("document.getElementById('view').dataset.look === 'face'", 10, "the face-id view")
    px = page.ev(PIXELS_JS)
    log(f"face-id view: {px['colours']} distinct colours over {px['differ']} hit pixels")
    assert px["sum"] != px_shaded["sum"], "the face-id view looks like the shaded one"
    assert px["colours"] >= 3, f"the face-id view has {px['colours']} colours"
    page.set_select("look", "iterations")
    page.b.wait_for("document.getElementById('view').dataset.look === 'iterations'"
                    " && !document.getElementById('legend').hidden", 10, "the iterations heat map and legend")
    step_latency(page, "iterations view, with AOVs")
    hover = hover_readout(page)
    log("hover (iterations view): " + hover.replace("\n", "; "))
    page.set_select("look", "shaded")


def step_compare(page):
    before = page.frames()
    page.ev("document.querySelector('button.view[data-view=\"iso\"]').click()")
    page.wait_final_after(before)
    page.scroll_to("compare")
    page.ev("document.getElementById('compare').click()")
    page.b.wait_for("document.getElementById('martin-newton-ms').textContent !== '–'"
                    " && !document.getElementById('compare').disabled", 120, "both methods' times")
    times = {m: page.ev(f"document.getElementById('{m}-newton-ms').textContent") for m in ("proposed", "martin")}
    bars = page.ev("document.querySelectorAll('#martin-histogram > div').length")
    log(f"compare methods: Newton stage proposed {times['proposed']} ms, martin {times['martin']} ms")
    for m, t in times.items():
        assert float(t) > 0, f"{m}: Newton time '{t}'"
    assert bars > 0, "no iteration histogram"


def render_exchanges(page, since):
    """(options sent or None, statistics answered) of each POST /v1/renders since `since` that finished."""
    sent, out = {}, []
    for e in page.b.events:
        if e["time"] < since:
            continue
        m, p = e["method"], e.get("params", {})
        if m == "Network.requestWillBeSent" and p["request"]["url"].endswith(RENDERS):
            sent[p["requestId"]] = p
        elif m == "Network.loadingFinished" and p["requestId"] in sent:
            rid = p["requestId"]
            body = page.b.call("Network.getResponseBody", requestId=rid)
            if body.get("base64Encoded"):  # an image answer (the EXR download), no statistics
                continue
            stats = json.loads(body["body"])["statistics"]
            options = None
            try:  # the multipart body, where Chromium keeps it (the options part is an in-memory blob)
                data = page.b.call("Network.getRequestPostData", requestId=rid)["postData"]
                start = data.find('{"')
                options = json.JSONDecoder().raw_decode(data[start:])[0] if start >= 0 else None
            except (RuntimeError, ValueError):
                pass
            out.append((options, stats))
    return out


def click(page, element_id):
    page.ev(f"document.getElementById('{element_id}').click()")


def step_image_options(page):
    """Shadows, then feature lines on: each re-renders, the answer's statistics say the stage ran, and the
    image changes; a drag with both on sends previews without anti-aliasing and shadows and a final with them."""
    page.set_select("look", "shaded")
    page.scroll_to("shadows")
    page.set_select("antialias", "4")
    px0 = page.ev(PIXELS_JS)
    since, before = time.monotonic(), page.frames()
    click(page, "shadows")
    page.wait_final_after(before)
    page.b.pump(0.2)
    px1 = page.ev(PIXELS_JS)
    options, stats = render_exchanges(page, since)[-1]
    sh = stats["shadows"]
    log(f"shadows on: {sh['shadowed_pixels']} of {stats['pixels_hit']} hit pixels shadowed, light map {sh['map_size']}, "
        f"shadow_map {stats['timings_ms']['shadow_map']:.1f} ms; options sent: {options}")
    assert sh["enabled"] and sh["map_size"] > 0 and sh["rays"] > 0, f"statistics.shadows: {sh}"
    assert options is None or options.get("shadows") is True, f"the page sent {options}"
    assert px1["sum"] != px0["sum"], "the image did not change with shadows on"
    stages = page.ev("[...document.querySelectorAll('#stages > div')].map(d => d.dataset.stage)")
    assert "shadow_map" in stages and "antialias" in stages, f"stage bar with shadows and anti-aliasing: {stages}"
    assert page.ev("!!document.querySelector('#stage-list .look-shadows')"), "the stage list does not report shadows"

    assert page.ev("document.getElementById('edge-width').disabled"), "line width enabled with the lines off"
    since, before = time.monotonic(), page.frames()
    click(page, "edges")
    page.wait_final_after(before)
    page.b.pump(0.2)
    px2 = page.ev(PIXELS_JS)
    options, stats = render_exchanges(page, since)[-1]
    log(f"feature lines on: edges {stats['timings_ms']['edges']:.1f} ms, antialias "
        f"{stats['antialias']['rays']} rays over {stats['antialias']['pixels']} pixels; options sent: {options}")
    assert stats["timings_ms"]["edges"] > 0, "no edges stage in the answer's timings"
    assert stats["shadows"]["enabled"] and stats["antialias"]["rays_per_edge_pixel"] == 4, stats["antialias"]
    assert options is None or (options.get("edges") is True and options.get("shadows") is True), options
    assert px2["sum"] != px1["sum"], "the image did not change with feature lines on"
    assert not page.ev("document.getElementById('edge-width').disabled"), "line width disabled with the lines on"
    stages = page.ev("[...document.querySelectorAll('#stages > div')].map(d => d.dataset.stage)")
    assert "edges" in stages, f"stage bar with feature lines: {stages}"

    # Orbiting with both on: quarter-size previews skip anti-aliasing and shadows, the release frame has them.
    since, before = time.monotonic(), page.frames()
    drag(page, 80, 12, 0.03)
    page.wait_final_after(before)
    page.b.pump(0.3)
    exchanges = render_exchanges(page, since)
    previews = [(o, s) for o, s in exchanges if s["width"] < 800]
    finals = [(o, s) for o, s in exchanges if s["width"] == 800]
    log(f"drag with shadows and lines: {len(previews)} previews answered, {len(finals)} full-size; previews "
        f"shadows {sorted({s['shadows']['enabled'] for _, s in previews})}, anti-aliasing "
        f"{sorted({s['antialias']['rays_per_edge_pixel'] for _, s in previews})}")
    assert previews and finals, f"{len(previews)} previews, {len(finals)} full-size frames"
    for o, s in previews:
        assert not s["shadows"]["enabled"] and s["antialias"]["rays_per_edge_pixel"] == 0, "a preview paid for the look"
        assert s["timings_ms"]["edges"] > 0, "a preview without its feature lines"
    o, s = finals[-1]
    assert s["shadows"]["enabled"] and s["antialias"]["rays_per_edge_pixel"] == 4 and s["timings_ms"]["edges"] > 0, \
        "the release frame lacks anti-aliasing, shadows or lines"

    # Off again, so that the later steps time the plain frame as before.
    before = page.frames()
    click(page, "shadows")
    page.wait_final_after(before)
    before = page.frames()
    click(page, "edges")
    page.wait_final_after(before)


def step_job(page, files, downloads):
    try:
        page.b.call("Browser.setDownloadBehavior", behavior="allow", downloadPath=str(downloads))
    except RuntimeError:  # older Chromium: the page-level (deprecated) form
        page.b.call("Page.setDownloadBehavior", behavior="allow", downloadPath=str(downloads))
    page.scroll_to("job-form")
    page.set_files("job-files", files)
    page.ev("document.querySelector('input[value=\"conversion:stl\"]').checked = true")
    page.ev("document.getElementById('job-submit').click()")
    state = page.b.wait_for("(() => { const j = document.querySelector('#job-list .job');"
                            " return j && ['succeeded','failed','canceled'].includes(j.dataset.state) ? j.dataset.state : ''; })()",
                            180, "the job to finish")
    rows = page.ev("document.querySelectorAll('#job-list .job tbody tr').length")
    percents = [int(p) for p in page.ev("document.querySelector('#job-list .job').dataset.percents").split(",") if p]
    caption = page.ev("document.querySelector('#job-list .job caption').textContent")
    streams = [e["params"]["request"] for e in page.b.events if e["method"] == "Network.requestWillBeSent"
               and e["params"]["request"]["url"].endswith("/events")]
    log(f"job: {state}, {rows} outputs; followed by {len(streams)} events stream(s), percentages shown {percents}; "
        f"'{caption}'")
    assert streams, "the job was not followed through its events stream"
    assert all(s["headers"].get("Accept") == "text/event-stream" for s in streams), streams
    assert percents and percents == sorted(percents) and percents[-1] == 100, percents
    assert "100 %" in caption, caption
    assert state == "succeeded", f"job ended {state}"
    assert rows == 2 * len(files), f"{rows} outputs listed"
    page.ev("document.querySelector('#job-list button.download').click()")
    deadline = time.monotonic() + 30
    while time.monotonic() < deadline:
        done = [p for p in downloads.iterdir() if not p.name.endswith(".crdownload")]
        if done:
            break
        page.b.pump(0.2)
    assert done, "no artifact was downloaded"
    data = done[0].read_bytes()
    log(f"downloaded artifact {done[0].name} ({len(data)} bytes)")
    assert data[:8] == b"\x89PNG\r\n\x1a\n", f"the artifact is not a PNG: {data[:16]!r}"


def step_conversion(page):
    page.set_select("convert-format", "stl")
    page.ev("document.getElementById('convert-submit').click()")
    text = page.b.wait_for("(() => { const t = document.getElementById('convert-result').textContent;"
                           " return t.includes('saved as') ? t : ''; })()", 120, "the conversion")
    log("conversion: " + text)


def step_accessibility(page):
    nodes = page.b.call("Accessibility.getFullAXTree")["nodes"]
    controls = {"button", "checkbox", "combobox", "textbox", "spinbutton", "slider", "radio", "link", "searchbox",
                "listbox", "switch", "menuitem", "ColorWell"}
    nameless, seen = [], 0
    for n in nodes:
        role = n.get("role", {}).get("value")
        if n.get("ignored") or role not in controls:
            continue
        seen += 1
        if not str(n.get("name", {}).get("value", "")).strip():
            nameless.append(f"{role} (backend node {n.get('backendDOMNodeId')})")
    log(f"accessibility: {seen} controls, {len(nameless)} without a name")
    assert seen >= 20, f"only {seen} controls in the accessibility tree"
    assert not nameless, f"controls without an accessible name: {nameless}"
    # The image options by name and role, as a screen reader announces them.
    root = page.b.call("DOM.getDocument")["root"]["nodeId"]
    wanted_names = {"antialias": ("combobox", "Anti-aliasing"), "edges": ("checkbox", "Feature lines"),
                    "edge-color": (None, "Line colour"), "edge-width": ("spinbutton", "Line width (px)"),
                    "shadows": ("checkbox", "Shadows")}
    for element_id, (role, name) in wanted_names.items():
        node = page.b.call("DOM.querySelector", nodeId=root, selector=f"#{element_id}")["nodeId"]
        ax = page.b.call("Accessibility.getPartialAXTree", nodeId=node, fetchRelatives=False)["nodes"][0]
        got_role, got_name = ax.get("role", {}).get("value"), str(ax.get("name", {}).get("value", "")).strip()
        assert not ax.get("ignored") and got_name.startswith(name) and (role is None or got_role == role), \
            f"#{element_id}: role {got_role}, name {got_name!r} (want {role} {name!r})"
    log(f"accessibility: image options named: {', '.join(n for _, n in wanted_names.values())}")
    # Tab order follows the page: key, file, views, options, image, ..., compare.
    page.ev("document.getElementById('api-key').focus()")
    order = []
    for _ in range(60):
        page.b.key("Tab", "Tab", 9)
        order.append(page.ev("document.activeElement.id || document.activeElement.dataset.view || document.activeElement.tagName"))
    wanted = ["key-save", "file", "iso", "resolution", "look", "view", "compare", "job-files", "convert-submit"]
    positions = [order.index(w) if w in order else -1 for w in wanted]
    log(f"tab order: {order[:24]}")
    assert -1 not in positions and positions == sorted(positions), f"tab order {order}"
    # The image is keyboard-operable: an arrow key re-renders the view.
    before = page.frames()
    page.ev("document.getElementById('view').focus()")
    page.b.key("ArrowLeft", "ArrowLeft", 37)
    page.wait_final_after(before)


def step_big_part_latency(page, part):
    """Release-to-full-frame latency on a cached part of about 300 faces at 800x600: the size of
    a typical mechanical part, where the orbiting viewer must still feel immediate."""
    page.scroll_to("file")
    page.set_select("look", "shaded")
    before = page.frames()
    t0 = time.monotonic()
    page.set_files("file", [part])
    page.wait_final_after(before, timeout=180)
    faces = page.ev("document.getElementById('status').textContent")
    log(f"{part.name}: first render in {time.monotonic() - t0:.1f} s ({faces})")
    step_latency(page, f"{part.name}, shaded view")
    page.set_select("look", "iterations")
    step_latency(page, f"{part.name}, iterations view, with AOVs")
    page.set_select("look", "shaded")
    # Measuring on it: the time to read its edges (NURBS JSON) and to find the snap under the pointer.
    click(page, "measure-toggle")
    page.b.wait_for("document.getElementById('measure-hint').textContent.startsWith('Click')", 120, "the model's edges")
    page.b.wait_for("(() => { const c = document.getElementById('view');"
                    " return c.dataset.final === '1' && c.dataset.busy === '0'; })()", 120, "the frame with normals")
    x, y, _ = page.canvas_centre()
    locate = []
    for dx in range(0, 40, 4):
        page.b.mouse("mouseMoved", x + dx, y, buttons=0)
        locate.append(float(page.ev("document.getElementById('measure-overlay').dataset.locateMs")))
    m = page.ev("({...document.getElementById('measure-overlay').dataset})")
    log(f"{part.name}, measuring: {m['vertices']} vertices and {m['segments']} edge segments read in {m['modelMs']} ms; "
        f"snap under the pointer median {statistics.median(locate):.1f} ms over {len(locate)} moves (max {max(locate):.1f})")
    step_latency(page, f"{part.name}, measuring (z, face and normal AOVs)")
    click(page, "measure-toggle")


def step_problem_shown(page, tmp):
    bad = pathlib.Path(tmp, "not-a-cad-file.step")
    bad.write_text("hello, this is not STEP\n")
    page.scroll_to("file")
    page.ev("document.getElementById('messages').replaceChildren()")
    page.set_files("file", [bad])
    text = page.b.wait_for("document.getElementById('messages').textContent", 30, "an error message")
    log(f"problem shown: {text}")
    assert "unsupported_format" in text and "HTTP 415" in text, text


def step_upload_once(page):
    """The file went up once (POST /v1/files); every frame since named it by id: no
    render request carried the file."""
    sent = [e["params"]["request"] for e in page.b.events if e["method"] == "Network.requestWillBeSent"]
    uploads = [r for r in sent if r["method"] == "POST" and r["url"].endswith("/v1/files")]
    renders = [r for r in sent if r["url"].endswith(RENDERS)]
    multipart = [r for r in renders if "multipart" in r["headers"].get("Content-Type", "")]
    log(f"upload once: {len(uploads)} upload(s) for {len(renders)} render requests, {len(multipart)} of them multipart")
    assert len(uploads) == 1 and len(renders) >= 10 and not multipart, (len(uploads), len(renders), len(multipart))


def step_failed_load(page, tmp):
    """A truncated STEP after a good file: the error shows, and nothing of the
    last model stays on screen (image, stage times, read-out)."""
    bad = pathlib.Path(tmp, "truncated.step")
    bad.write_bytes(pathlib.Path("/usr/share/opencascade/data/step/screw.step").read_bytes()[:30000])
    frames = page.frames()
    cleared = int(page.ev("Number(document.getElementById('view').dataset.cleared || 0)"))
    page.scroll_to("file")
    page.ev("document.getElementById('messages').replaceChildren()")
    page.set_files("file", [bad])
    text = page.b.wait_for("document.getElementById('messages').textContent", 60, "an error message")
    state = page.ev("""(() => {
      const c = document.getElementById('view');
      const px = c.width && c.height ? c.getContext('2d').getImageData(0, 0, c.width, c.height).data : [];
      return {cleared: Number(c.dataset.cleared || 0), final: c.dataset.final, painted: px.some((v) => v !== 0),
              stages: document.getElementById('stage-list').children.length,
              hover: document.getElementById('hover').textContent, name: document.getElementById('file-name').textContent};
    })()""")
    log(f"failed load: {text!r}; {state}")
    assert state["cleared"] > cleared and state["final"] != "1" and not state["painted"], state
    assert state["stages"] == 0 and state["hover"] == "" and "truncated.step" in state["name"], state
    assert page.frames() == frames, "a frame was shown for the failed file"


def step_link_reopens(page):
    """The address holds the stored file and the view: opening it in a new page
    shows that file in that view without an upload."""
    page.ev("document.querySelector('button.view[data-view=\"top\"]').click()")
    page.b.wait_for("location.hash.includes('view=top')", 10, "the view in the address")
    link = page.ev("location.href")
    uploads = lambda: sum(1 for e in page.b.events if e["method"] == "Network.requestWillBeSent"
                          and e["params"]["request"]["method"] == "POST"
                          and e["params"]["request"]["url"].endswith("/v1/files"))
    before = uploads()
    page.b.call("Page.navigate", url="about:blank")
    page.b.pump(0.3)
    page.b.call("Page.navigate", url=link)
    page.b.wait_for("document.body && document.body.dataset.ready === '1'", 30, "the page's modules")
    page.wait_final_after(0)
    pressed = page.ev("document.querySelector('button.view[aria-pressed=\"true\"]')?.dataset.view")
    name = page.ev("document.getElementById('file-name').textContent")
    log(f"link {link.split('#')[1][:24]}...: reopened {name!r} in view {pressed}, {uploads() - before} uploads")
    assert pressed == "top" and "screw" in name and uploads() == before, (pressed, name)


def final_exchange(page, action, what):
    """Runs `action` (JS), waits for the full-size frame; (options sent, statistics answered) of it."""
    since, before = time.monotonic(), page.frames()
    page.ev(action)
    page.wait_final_after(before)
    page.b.pump(0.2)
    exchanges = render_exchanges(page, since)
    assert exchanges, f"no render for {what}"
    return exchanges[-1]


def drag_section(page, positions):
    """Drags the section's position slider through `positions` (previews), then releases it (the full frame);
    the (options, statistics) of the renders since, and the previews' statistics."""
    since, before = time.monotonic(), page.frames()
    for t in positions:
        page.ev(f"(() => {{ const r = document.getElementById('section-at'); r.value = '{t}';"
                f" r.dispatchEvent(new Event('input')); }})()")
        page.b.pump(0.15)
    page.ev("document.getElementById('section-at').dispatchEvent(new Event('change'))")
    page.wait_final_after(before)
    page.b.pump(0.2)
    frames = render_exchanges(page, since)
    return frames, [st for o, st in frames if st["width"] < 800]


def pick_parts(page, parts):
    """Clicks on a grid over the image: each click on the model names the part under the pointer (the
    parts panel's row is marked and focused, the hint says which face); the face is checked against the
    part's face ranges in the stored file's summary, fetched here (GET /v1/files/{id}) and not the page's."""
    file_id = urllib.parse.parse_qs(page.ev("location.hash.slice(1)"))["file"][0]
    req = urllib.request.Request(f"{URL}/v1/files/{file_id}", headers={"Authorization": f"Bearer {KEY}"})
    with urllib.request.urlopen(req, timeout=30) as r:
        summary = json.loads(r.read())["summary"]
    ranges = {p["id"]: p["face_ranges"] for p in summary["parts"]}
    picked = {}
    grid = [(i / 8, j / 6) for j in range(1, 6) for i in range(1, 8)]
    for u, v in grid:
        # Where the image is now: the parts panel opens above it at the first pick, and
        # focusing a part's row scrolls the page.
        page.scroll_to("view")
        _, _, (left, top, width, height) = page.canvas_centre()
        x, y = left + width * u, top + height * v
        page.ev("document.getElementById('parts-hint').textContent = ''")  # this click's answer, not the last
        page.b.mouse("mousePressed", x, y)
        page.b.mouse("mouseReleased", x, y, buttons=0)
        # The first click may wait for a frame with face ids (the page asks for one and then picks).
        hint = page.b.wait_for("(() => { const t = document.getElementById('parts-hint').textContent;"
                               " return t && !t.startsWith('Finding') ? t : ''; })()", 30, "the part picked")
        row = page.ev("(() => { const li = document.querySelector('#parts li.picked');"
                      " return li ? li.querySelector('select').dataset.part : ''; })()")
        m = re.match(r"Face (\d+): part (\S+) ", hint)
        if not m:
            assert not row and hint.startswith("Nothing there"), (hint, row)
            continue
        face, part = int(m.group(1)), m.group(2)
        assert row == part and part in parts, (hint, row)
        assert page.ev("document.activeElement.dataset.part") == part
        assert any(a <= face <= b for a, b in ranges[part]), (face, part, ranges[part])
        picked[part] = face
    log(f"pick a part: {len(picked)} parts picked by {len(grid)} clicks, a face of each: {picked}")
    assert len(picked) >= 2, picked
    page.b.screenshot(ARTIFACTS / "pick-part.png")


def step_cad_views(page, assembly):
    """An assembly: the parts panel lists its tree; hide, isolate and ghost a part; a section across Z
    with caps, dragged along (previews while dragging, the exact frame on release); explode. Each
    final frame's statistics say what the service did, and no request prepared the scene again."""
    before = page.frames()
    page.scroll_to("file")
    page.set_files("file", [assembly])
    page.wait_final_after(before)
    parts = page.ev("[...document.querySelectorAll('#parts select')].map((s) => s.dataset.part)")
    log(f"CAD views: parts panel {parts}")
    assert len(parts) >= 3 and not page.ev("document.getElementById('parts-box').hidden"), parts
    pick_parts(page, parts)
    leaf = parts[-1]
    set_part = lambda state: (f"(() => {{ const s = document.querySelector('#parts select[data-part=\"{leaf}\"]');"
                              f" s.value = '{state}'; s.dispatchEvent(new Event('change')); }})()")
    results = {}
    for state, field in (("hide", "hidden_faces"), ("only", "hidden_faces"), ("ghost", "ghost_faces")):
        options, stats = final_exchange(page, set_part(state), state)
        results[state] = stats["parts"][field]
        assert stats["parts"][field] > 0 and stats["timings_ms"].get("prepare", 0) == 0, (state, stats["parts"])
        assert options is None or leaf in options["parts"][state], options
    page.ev(set_part("shown"))
    page.wait_final_after(page.frames() - 1)
    _, stats = final_exchange(page, "(() => { const s = document.getElementById('section-axis'); s.value = '2';"
                                    " s.dispatchEvent(new Event('change')); })()", "a section")
    caps0 = stats["sections"]["cap_pixels"]
    assert stats["sections"]["planes"] == 1 and caps0 > 0, stats["sections"]
    drag_frames, previews = drag_section(page, (0.45, 0.4, 0.35, 0.3))
    log(f"section drag: {len(previews)} previews, then the full frame; caps {caps0} -> "
        f"{drag_frames[-1][1]['sections']['cap_pixels']} pixels")
    assert previews and drag_frames[-1][1]["width"] == 800 and drag_frames[-1][1]["sections"]["cap_pixels"] > 0
    page.ev("(() => { const s = document.getElementById('section-axis'); s.value = '';"
            " s.dispatchEvent(new Event('change')); })()")
    page.wait_final_after(page.frames() - 1)
    _, stats = final_exchange(page, "(() => { const r = document.getElementById('explode'); r.value = '0.5';"
                                    " r.dispatchEvent(new Event('change')); })()", "explode")
    log(f"explode 0.5: {stats['parts']['moved_faces']} faces moved, prepare {stats['timings_ms'].get('prepare', 0)} ms")
    assert stats["parts"]["moved_faces"] > 0 and stats["timings_ms"].get("prepare", 0) == 0, stats["parts"]
    page.ev("window.scrollTo(0, 0)")
    page.b.pump(0.2)
    page.b.screenshot(ARTIFACTS / "cad-explode.png")
    _, stats = final_exchange(page, "document.getElementById('sheet').click()", "the 4-view sheet")
    size = page.ev("[document.getElementById('view').width, document.getElementById('view').height]")
    log(f"4-view sheet: {[v['view'] for v in stats['views']]}, canvas {size}")
    assert [v["view"] for v in stats["views"]] == ["front", "top", "right", "iso"] and size == [1600, 1200], size
    page.ev("window.scrollTo(0, 0)")
    page.b.pump(0.2)
    page.b.screenshot(ARTIFACTS / "cad-sheet.png")
    # Projection: the named views are orthographic; the switch keeps the view's size at the target,
    # and an orbit keeps the projection chosen.
    for projection in ("perspective", "orthographic"):
        _, stats = final_exchange(page, f"(() => {{ const s = document.getElementById('projection');"
                                        f" s.value = '{projection}'; s.dispatchEvent(new Event('change')); }})()",
                                  projection)
        assert stats["camera"]["projection"] == projection, stats["camera"]
    since, before = time.monotonic(), page.frames()
    drag(page, 60, 6, 0.05)
    page.wait_final_after(before)
    page.b.pump(0.2)
    cam = render_exchanges(page, since)[-1][1]["camera"]
    log(f"projection: both ways, an orbit stays {cam['projection']} (ortho_height {cam.get('ortho_height')})")
    assert cam["projection"] == "orthographic" and cam["ortho_height"] > 0, cam


# The 10 mm cube of `nurbsrt_fixture cube10` (tests/support/fixtures.h: kCube10Corner).
CUBE_CORNER, CUBE_SIZE = (5.0, -3.0, 2.0), 10.0


def project(camera, p, width, height):
    """Where the point p falls in the frame (continuous pixel position) and its distance
    along the view direction: the renderer's camera contract (renderer/camera.h), written
    again here so that the page's projection is checked against an independent one."""
    sub = lambda a, b: [a[i] - b[i] for i in range(3)]
    dot = lambda a, b: sum(a[i] * b[i] for i in range(3))
    cross = lambda a, b: [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
    unit = lambda a: [x / dot(a, a) ** 0.5 for x in a]
    f = unit(sub(camera["target"], camera["eye"]))
    r = unit(cross(f, camera["up"]))
    u = cross(r, f)
    d = sub(p, camera["eye"])
    if camera["projection"] == "orthographic":
        half = camera["ortho_height"] / 2
        sx, sy = dot(r, d) / half, dot(u, d) / half
    else:
        import math
        tan = math.tan(math.radians(camera["fov_deg"]) / 2)
        sx, sy = dot(r, d) / (dot(f, d) * tan), dot(u, d) / (dot(f, d) * tan)
    return (sx * height / width + 1) * 0.5 * width, (1 - sy) * 0.5 * height, dot(f, d)


def step_measure(page, cube, cylinder, shot):
    """Exact measuring on a 10 mm cube: snapped to two vertices of an edge the distance reads
    10.000 mm within 1e-4 mm; the angle between two adjacent faces 90 degrees; a vertex's
    coordinates; Esc cancels a pick, the keyboard picks, the results clear."""
    page.scroll_to("file")
    page.set_select("look", "shaded")
    since, before = time.monotonic(), page.frames()
    page.set_files("file", [cube])
    page.wait_final_after(before)
    before = page.frames()
    click(page, "measure-toggle")
    assert page.ev("document.getElementById('measure-toggle').getAttribute('aria-pressed')") == "true"
    page.wait_final_after(before)  # the frame again with the normals measuring reads
    page.b.wait_for("document.getElementById('measure-hint').textContent.startsWith('Click')", 60,
                    "the model's edges")
    page.b.pump(0.2)
    cam = {"camera": render_exchanges(page, since)[-1][1]["camera"]}
    vertices = page.ev("Number(document.getElementById('measure-overlay').dataset.vertices)")
    lo = CUBE_CORNER
    corners = [[lo[0] + CUBE_SIZE * i, lo[1] + CUBE_SIZE * j, lo[2] + CUBE_SIZE * k]
               for i in (0, 1) for j in (0, 1) for k in (0, 1)]
    size = page.ev("[document.getElementById('view').width, document.getElementById('view').height]")
    _, _, rect = page.canvas_centre()
    to_client = lambda x, y: (rect[0] + x * rect[2] / size[0], rect[1] + y * rect[3] / size[1])
    screen = {tuple(c): project(cam["camera"], c, *size) for c in corners}
    near = min(corners, key=lambda c: screen[tuple(c)][2])  # the corner nearest the eye: seen
    ends = [c for c in corners if sum(a != b for a, b in zip(c, near)) == 1]  # its three edges' other ends
    log(f"measure: {vertices} model vertices; nearest corner {near}, camera {cam['camera']['projection']}")

    def pick_at(p, offset, wanted_snap):
        x, y, _ = project(cam["camera"], p, *size)
        cx, cy = to_client(x + offset[0], y + offset[1])
        page.b.mouse("mouseMoved", cx - 1, cy, buttons=0)
        page.b.mouse("mouseMoved", cx, cy, buttons=0)
        if wanted_snap:
            page.b.wait_for(f"document.getElementById('view').dataset.snap === '{wanted_snap}'", 10,
                            f"a {wanted_snap} snap near {p}")
        page.b.mouse("mousePressed", cx, cy)
        page.b.mouse("mouseReleased", cx, cy, buttons=0)

    def last_result(count):
        page.b.wait_for(f"document.querySelectorAll('#measure-results li').length === {count}", 10, f"result {count}")
        return page.ev("(() => { const li = [...document.querySelectorAll('#measure-results li')].pop();"
                       " return {text: li.textContent, value: JSON.parse(li.dataset.value), snaps: li.dataset.snaps,"
                       " precision: Number(li.dataset.precision)}; })()")

    def set_projection(projection):
        since, before = time.monotonic(), page.frames()
        page.set_select("projection", projection)
        page.wait_final_after(before)
        page.b.pump(0.2)
        cam["camera"] = render_exchanges(page, since)[-1][1]["camera"]
        assert cam["camera"]["projection"] == projection, cam

    def measure_edge(end, count):
        """The edge from `near` to `end`, each vertex picked 3 px beside it: the snaps take the exact vertices."""
        pick_at(near, (3, -2), "vertex")
        pick_at(end, (-2, 3), "vertex")
        r = last_result(count)
        log(f"measure, {cam['camera']['projection']}: edge {near} - {end}: {r['text']} "
            f"(|d - 10 mm| = {abs(r['value'] - CUBE_SIZE):.1e} mm)")
        assert r["snaps"] == "vertex vertex" and abs(r["value"] - CUBE_SIZE) <= 1e-4 and "10.000" in r["text"], r

    measure_edge(ends[0], 1)
    set_projection("perspective")  # the other camera of the contract
    measure_edge(ends[1], 2)
    set_projection("orthographic")

    page.set_select("measure-kind", "angle")
    face_a = [near[i] + 0.35 * (ends[0][i] - near[i]) + 0.35 * (ends[1][i] - near[i]) for i in range(3)]
    face_b = [near[i] + 0.35 * (ends[1][i] - near[i]) + 0.35 * (ends[2][i] - near[i]) for i in range(3)]
    pick_at(face_a, (0, 0), "surface")
    pick_at(face_b, (0, 0), "surface")
    r = last_result(3)
    log(f"measure: {r['text']} (|a - 90°| = {abs(r['value'] - 90.0):.1e}°)")
    assert abs(r["value"] - 90.0) <= 1e-3 and "90.000" in r["text"], r

    page.set_select("measure-kind", "point")
    pick_at(near, (2, 2), "vertex")
    r = last_result(4)
    log(f"measure: {r['text']}")
    assert max(abs(a - b) for a, b in zip(r["value"], near)) <= 1e-4, (r, near)
    # Without snapping, a surface point: on the face's plane within the precision it shows.
    click(page, "measure-snap")
    pick_at(face_a, (0, 0), "surface")
    r = last_result(5)
    k = next(i for i in range(3) if ends[2][i] != near[i])  # the axis across face_a's plane
    log(f"measure: {r['text']} (off the plane by {abs(r['value'][k] - near[k]):.1e} mm)")
    assert r["snaps"] == "surface" and abs(r["value"][k] - near[k]) <= r["precision"] < 1e-5, (r, near)
    click(page, "measure-snap")

    # Esc cancels a measurement under way; the keyboard moves a cursor and picks.
    page.set_select("measure-kind", "distance")
    pick_at(face_a, (0, 0), None)
    assert "second point" in page.ev("document.getElementById('measure-hint').textContent")
    page.ev("document.getElementById('view').focus()")
    page.b.key("Escape", "Escape", 27)
    assert "first point" in page.ev("document.getElementById('measure-hint').textContent"), "Esc did not cancel"
    frames = page.frames()
    for _ in range(3):
        page.b.key("ArrowRight", "ArrowRight", 39)
    page.b.key("Enter", "Enter", 13, text="\r")
    page.b.key("ArrowDown", "ArrowDown", 40, shift=True)
    page.b.key("Enter", "Enter", 13, text="\r")
    r = last_result(6)
    log(f"measure, by keyboard: {r['text']}")
    assert page.frames() == frames, "the measuring keys orbited the view"
    page.ev("window.scrollTo(0, 0)")
    page.b.mouse("mouseMoved", *to_client(*project(cam["camera"], ends[1], *size)[:2]), buttons=0)
    page.b.pump(0.3)
    page.b.screenshot(ARTIFACTS / "measure.png")
    if shot:
        page.b.screenshot(shot)
        log(f"screenshot saved to {shot}")
    click(page, "measure-clear")
    assert page.ev("document.querySelectorAll('#measure-results li').length") == 0, "the results were not cleared"
    if cylinder:
        step_measure_curved(page, cylinder)
    page.ev("document.getElementById('view').focus()")
    page.b.key("Escape", "Escape", 27)
    assert page.ev("document.getElementById('measure-toggle').getAttribute('aria-pressed')") == "false", \
        "Esc with nothing under way did not leave measuring"


def step_measure_curved(page, cylinder):
    """A point snapped to the top rim of a cylinder (r 10, h 30, axis Z: `nurbsrt_fixture cylinder`)
    lies on that circle within the precision the page shows for it, at most 1e-6 mm: made exact
    where the top face meets the side, not left on the trim loop's samples."""
    import math
    page.scroll_to("file")
    since, before = time.monotonic(), page.frames()
    page.set_files("file", [cylinder])
    page.wait_final_after(before)
    page.b.wait_for("document.getElementById('measure-overlay').dataset.modelMs", 60, "the cylinder's edges")
    page.b.wait_for("(() => { const c = document.getElementById('view');"
                    " return c.dataset.final === '1' && c.dataset.busy === '0'; })()", 60, "the frame with normals")
    page.b.pump(0.2)
    camera = render_exchanges(page, since)[-1][1]["camera"]
    page.set_select("measure-kind", "point")
    size = page.ev("[document.getElementById('view').width, document.getElementById('view').height]")
    _, _, rect = page.canvas_centre()
    # The rim's point nearest the eye (seen), 3 px off it towards the cylinder's inside.
    eye = camera["eye"]
    angle = math.atan2(eye[1], eye[0])
    rim = [10 * math.cos(angle + 0.3), 10 * math.sin(angle + 0.3), 30.0]
    x, y, _ = project(camera, rim, *size)
    cx, cy = rect[0] + x * rect[2] / size[0], rect[1] + (y + 3) * rect[3] / size[1]
    page.b.mouse("mouseMoved", cx - 1, cy, buttons=0)
    page.b.mouse("mouseMoved", cx, cy, buttons=0)
    page.b.wait_for("document.getElementById('view').dataset.snap === 'edge'", 10, "an edge snap on the rim")
    count = page.ev("document.querySelectorAll('#measure-results li').length")
    page.b.mouse("mousePressed", cx, cy)
    page.b.mouse("mouseReleased", cx, cy, buttons=0)
    page.b.wait_for(f"document.querySelectorAll('#measure-results li').length === {count + 1}", 10, "the point")
    r = page.ev("(() => { const li = [...document.querySelectorAll('#measure-results li')].pop();"
                " return {text: li.textContent, value: JSON.parse(li.dataset.value), precision: Number(li.dataset.precision)}; })()")
    p = r["value"]
    off = max(abs(math.hypot(p[0], p[1]) - 10), abs(p[2] - 30))
    log(f"measure, curved edge: {r['text']} (off the rim circle by {off:.1e} mm)")
    # Moved onto the true edge (the plane meets the cylinder there), not left on the loop's samples.
    assert off <= r["precision"] <= 1e-6, r
    click(page, "measure-clear")


def step_stored_files(page):
    """The stored-files panel lists what was uploaded (GET /v1/files); a click reopens one by id, without an upload."""
    uploads = lambda: sum(1 for e in page.b.events if e["method"] == "Network.requestWillBeSent"
                          and e["params"]["request"]["method"] == "POST"
                          and e["params"]["request"]["url"].endswith("/v1/files"))
    before_uploads, before = uploads(), page.frames()
    page.scroll_to("stored-box")
    loaded = int(page.ev("Number(document.getElementById('stored-files').dataset.loaded || 0)"))
    page.ev("document.querySelector('#stored-box summary').click()")
    page.b.wait_for(f"Number(document.getElementById('stored-files').dataset.loaded || 0) > {loaded}", 10, "the list")
    names = page.ev("[...document.querySelectorAll('#stored-files button.reopen')].map((b) => b.textContent)")
    log(f"stored files: {names}")
    assert "screw.step" in names, names
    page.ev("[...document.querySelectorAll('#stored-files button.reopen')].find((b) => b.textContent === 'screw.step').click()")
    page.wait_final_after(before)
    name = page.ev("document.getElementById('file-name').textContent")
    log(f"stored files: reopened {name!r}, {uploads() - before_uploads} uploads")
    assert "screw.step" in name and uploads() == before_uploads, (name, uploads() - before_uploads)
    page.ev("document.querySelector('#stored-box summary').click()")


def step_narrow(page):
    """At a phone's width (390 px) nothing is wider than the viewport."""
    page.b.call("Emulation.setDeviceMetricsOverride", width=390, height=844, deviceScaleFactor=1, mobile=True)
    page.b.pump(0.5)
    m = page.ev("""(() => ({doc: document.documentElement.scrollWidth, view: window.innerWidth,
      wide: [...document.querySelectorAll('body *')].filter((e) => e.getBoundingClientRect().right > window.innerWidth + 0.5)
             .slice(0, 8).map((e) => e.id || e.className || e.tagName)}))()""")
    page.ev("window.scrollTo(0, 0)")
    page.b.pump(0.2)
    page.b.screenshot(ARTIFACTS / "narrow-390.png")
    log(f"390 px layout: document {m['doc']} px wide in a {m['view']} px viewport; wider elements {m['wide']}")
    page.b.call("Emulation.setDeviceMetricsOverride", width=1400, height=1100, deviceScaleFactor=1, mobile=False)
    page.b.pump(0.3)
    assert m["doc"] <= m["view"], m


def step_elapsed(page):
    """A render in flight shows its elapsed seconds ticking; the landed frame its final time."""
    page.scroll_to("resolution")
    page.ev("""(() => { window.busyTexts = []; const t = document.getElementById('busy-text');
      new MutationObserver(() => window.busyTexts.push(t.textContent)).observe(t, {childList: true, characterData: true,
        subtree: true}); })()""")
    before = page.frames()
    # A slower frame (16 rays per edge pixel, 1600x1200), so that the seconds tick; one request.
    page.ev("document.getElementById('antialias').value = '16'")
    page.set_select("resolution", "1600x1200")
    page.wait_final_after(before)
    ticks = page.ev("window.busyTexts")
    status = page.ev("document.getElementById('status').textContent")
    final = float(page.ev("document.getElementById('view').dataset.elapsedS"))
    shown = [float(t.split("…")[1].split("s")[0]) for t in ticks if "…" in t]
    log(f"elapsed time: {len(shown)} ticks {shown[:3]}...{shown[-2:]}; status ends '{status[-40:]}'")
    assert len(set(shown)) >= 2 and shown == sorted(shown), f"the seconds did not tick: {ticks}"
    assert f"on screen {final:.1f} s after the request" in status and final >= shown[-1], (status, shown)
    before = page.frames()
    page.ev("document.getElementById('antialias').value = '4'")
    page.set_select("resolution", "800x600")
    page.wait_final_after(before)


def exr_channels(path):
    """The channel names of an OpenEXR file: OpenImageIO's oiiotool where Debian's openimageio-tools is
    installed, else the header's `channels` attribute read directly (OpenEXR file layout: magic, version,
    then name\\0 type\\0 size value attributes; chlist: name\\0 then 16 bytes per channel, ended by \\0)."""
    tool = shutil.which("oiiotool")
    if tool:
        out = subprocess.run([tool, "--info", "-v", str(path)], capture_output=True, text=True, check=True).stdout
        line = next(l for l in out.splitlines() if "channel list:" in l)
        return [c.strip() for c in line.split("channel list:")[1].split(",")], "oiiotool"
    data = path.read_bytes()
    assert data[:4] == b"\x76\x2f\x31\x01", f"not an OpenEXR file: {data[:8]!r}"
    at = 8
    while data[at] != 0:
        name_end = data.index(b"\0", at)
        type_end = data.index(b"\0", name_end + 1)
        size = struct.unpack_from("<i", data, type_end + 1)[0]
        value = data[type_end + 5:type_end + 5 + size]
        if data[at:name_end] == b"channels":
            names, i = [], 0
            while value[i] != 0:
                end = value.index(b"\0", i)
                names.append(value[i:end].decode())
                i = end + 1 + 16
            return names, "the file's header"
        at = type_end + 5 + size
    raise AssertionError("no channels attribute in the EXR header")


def step_exr_download(page, downloads):
    """Save EXR with AOVs: a render of the view on screen as OpenEXR, saved with the key; its channels read."""
    page.b.call("Browser.setDownloadBehavior", behavior="allow", downloadPath=str(downloads))
    page.scroll_to("save-exr")
    click(page, "save-exr")
    status = page.b.wait_for("(() => { const t = document.getElementById('save-status').textContent;"
                             " return t.startsWith('saved') ? t : ''; })()", 120, "the EXR")
    deadline = time.monotonic() + 30
    while time.monotonic() < deadline:
        done = [p for p in downloads.iterdir() if p.suffix == ".exr"]
        if done:
            break
        page.b.pump(0.2)
    assert done, "no EXR was downloaded"
    names, how = exr_channels(done[0])
    log(f"EXR download: {status}; channels ({how}) {names}")
    assert {"R", "G", "B", "A", "Z", "face", "N.X", "N.Y", "N.Z", "u", "v", "iterations"} <= set(names), names


def step_wide(page):
    """At 1920x1080 the controls stand beside the image, the image is not scaled past its pixels and nothing
    is wider than the viewport."""
    page.b.call("Emulation.setDeviceMetricsOverride", width=1920, height=1080, deviceScaleFactor=1, mobile=False)
    page.b.pump(0.5)
    m = page.ev("""(() => { const r = (s) => document.querySelector(s).getBoundingClientRect();
      const c = r('.controls'), p = r('#view');
      return {doc: document.documentElement.scrollWidth, view: window.innerWidth, controlsRight: c.right, imageLeft: p.left,
        controlsTop: c.top, imageTop: p.top, imageBottom: p.bottom, shown: p.width, pixels: document.getElementById('view').width}; })()""")
    page.ev("window.scrollTo(0, 0)")
    page.b.pump(0.2)
    page.b.screenshot(ARTIFACTS / "wide-1920.png")
    log(f"1920 px layout: document {m['doc']} px wide in a {m['view']} px viewport; controls end at x {m['controlsRight']:.0f},"
        f" image from x {m['imageLeft']:.0f}, shown {m['shown']:.0f} px wide for {m['pixels']} pixels")
    page.b.call("Emulation.setDeviceMetricsOverride", width=1400, height=1100, deviceScaleFactor=1, mobile=False)
    page.b.pump(0.3)
    assert m["doc"] <= m["view"], m
    assert m["controlsRight"] <= m["imageLeft"] and m["controlsTop"] < m["imageBottom"], f"not side by side: {m}"
    assert m["shown"] <= m["pixels"] + 0.5, f"the image is stretched past its pixels: {m}"


def step_section_from_face(page, cube):
    """Section from a clicked face: on the 10 mm cube's front view, the plane goes through the clicked exact
    surface point with the face's normal towards the eye; dragged along it (previews, then the exact frame)
    it cuts the cube and shows caps; flip turns the normal."""
    page.scroll_to("file")
    page.set_select("look", "shaded")
    before = page.frames()
    page.set_files("file", [cube])
    page.wait_final_after(before)
    before = page.frames()
    page.ev("document.querySelector('button.view[data-view=\"front\"]').click()")
    page.wait_final_after(before)
    since, before = time.monotonic(), page.frames()
    if page.ev("document.getElementById('measure-toggle').getAttribute('aria-pressed')") == "true":
        click(page, "measure-toggle")  # a click in the measuring mode measures
    page.set_select("section-axis", "face")
    if page.ev("document.getElementById('view').dataset.busy") == "1":
        page.wait_final_after(before)  # the frame again with the normals the pick reads
    page.scroll_to("view")
    page.b.pump(0.2)
    x, y, _ = page.canvas_centre()
    before = page.frames()
    page.b.mouse("mousePressed", x + 7, y - 5)
    page.b.mouse("mouseReleased", x + 7, y - 5, buttons=0)
    page.wait_final_after(before)
    page.b.pump(0.2)
    options, stats = render_exchanges(page, since)[-1]
    cam = stats["camera"]
    eye_dir = [e - t for e, t in zip(cam["eye"], cam["target"])]
    length = sum(c * c for c in eye_dir) ** 0.5
    eye_dir = [c / length for c in eye_dir]
    plane = options["sections"][0]
    k = max(range(3), key=lambda i: abs(eye_dir[i]))
    face_at = CUBE_CORNER[k] + (CUBE_SIZE if eye_dir[k] > 0 else 0)  # the front face's plane: the side the eye sees
    log(f"section from face: clicked plane point {plane['point']} normal {plane['normal']}; face normal towards the"
        f" eye {eye_dir}; the face's plane at coordinate {k} = {face_at}")
    assert max(abs(a - b) for a, b in zip(plane["normal"], eye_dir)) <= 1e-6, (plane, eye_dir)
    assert abs(plane["point"][k] - face_at) <= 1e-4, (plane["point"], face_at)
    at = float(page.ev("document.getElementById('section-at').value"))
    frames, previews = drag_section(page, [at - d for d in (0.1, 0.2, 0.3, 0.4)])
    options, stats = frames[-1]
    moved = options["sections"][0]
    depth = face_at - moved["point"][k] if eye_dir[k] > 0 else moved["point"][k] - face_at
    log(f"section from face dragged: {len(previews)} previews, then the full frame; plane {depth:.3f} mm inside,"
        f" caps {stats['sections']['cap_pixels']} pixels")
    assert previews and stats["width"] == 800 and stats["sections"]["cap_pixels"] > 0, stats["sections"]
    assert moved["normal"] == plane["normal"] and 0 < depth < CUBE_SIZE, moved
    page.ev("window.scrollTo(0, 0)")
    page.b.pump(0.2)
    page.b.screenshot(ARTIFACTS / "section-from-face.png")
    options, stats = final_exchange(page, "document.getElementById('section-flip').click()", "flip")
    assert options["sections"][0]["normal"] == [-c for c in plane["normal"]], options["sections"]
    page.set_select("section-axis", "")
    page.wait_final_after(page.frames() - 1)


def step_csp_enforced(page):
    """The browser enforces the page's policy: an injected inline script does not run."""
    directive = page.ev("""new Promise((resolve) => {
      document.addEventListener('securitypolicyviolation', (e) => resolve(e.effectiveDirective), {once: true});
      const s = document.createElement('script');
      s.textContent = 'window.inlineRan = true';
      document.body.append(s);
      setTimeout(() => resolve('no violation'), 2000);
    })""")
    ran = page.ev("window.inlineRan === true")
    log(f"CSP: an inline script was refused ({directive})")
    assert directive.startswith("script-src") and not ran, (directive, ran)


def main():
    step_file, other_file = map(pathlib.Path, sys.argv[1:3])
    big_part = pathlib.Path(sys.argv[3]) if len(sys.argv) > 3 and pathlib.Path(sys.argv[3]).is_file() else None
    assembly = pathlib.Path(sys.argv[4]) if len(sys.argv) > 4 and pathlib.Path(sys.argv[4]).is_file() else None
    cube = pathlib.Path(sys.argv[5]) if len(sys.argv) > 5 and pathlib.Path(sys.argv[5]).is_file() else None
    cylinder = pathlib.Path(sys.argv[6]) if len(sys.argv) > 6 and pathlib.Path(sys.argv[6]).is_file() else None
    chromium = find_chromium()
    ARTIFACTS.mkdir(parents=True, exist_ok=True)
    tmp = tempfile.mkdtemp(prefix="nurbsrt-web-test-")
    downloads = pathlib.Path(tmp, "downloads")
    downloads.mkdir()
    browser = Browser(chromium)
    page = Page(browser)
    current = "start"
    try:
        for domain in ("Runtime", "Log", "Network", "Page", "DOM", "Accessibility"):
            browser.call(f"{domain}.enable")
        browser.call("Emulation.setDeviceMetricsOverride", width=1400, height=1100, deviceScaleFactor=1, mobile=False)
        current = "load"; step_load(page)
        if ONLY == "viewer":  # a quick run of the viewer steps of this file alone, while working on them
            current = "upload"; step_upload(page, step_file)
            current = "elapsed"; step_elapsed(page)
            current = "EXR download"; step_exr_download(page, downloads)
            current = "wide"; step_wide(page)
            current = "section from face"; step_section_from_face(page, cube)
            log("the viewer steps passed (NURBSRT_WEB_ONLY=viewer: no other step ran)")
            return 0
        if ONLY == "measure":  # a quick run of the measuring step alone, while working on it
            current = "upload"; step_upload(page, step_file)
            current = "measure"; step_measure(page, cube, cylinder, MEASURE_SCREENSHOT)
            current = "stored files"; step_stored_files(page)
            log("the measuring and stored-files steps passed (NURBSRT_WEB_ONLY=measure: no other step ran)")
            return 0
        current = "upload"; px = step_upload(page, step_file)
        current = "orbit"; px = step_orbit(page, px)
        current = "latency"; step_latency(page, "shaded view")
        px = page.ev(PIXELS_JS)
        current = "look inside"; step_look_inside(page, px)
        current = "compare"; step_compare(page)
        current = "image options"; step_image_options(page)
        if SCREENSHOT:
            before = page.frames()
            page.set_select("look", "face")  # the Iso frame has no AOVs yet: fetched now
            page.wait_final_after(before)
            page.b.wait_for("document.getElementById('view').dataset.look === 'face'", 10, "the face-id view")
            page.ev("window.scrollTo(0, 0)")
            browser.pump(0.3)
            browser.screenshot(SCREENSHOT)
            log(f"screenshot saved to {SCREENSHOT}")
            page.set_select("look", "shaded")
        current = "upload once"; step_upload_once(page)
        current = "link"; step_link_reopens(page)
        current = "narrow"; step_narrow(page)
        current = "wide"; step_wide(page)
        current = "elapsed"; step_elapsed(page)
        current = "job"; step_job(page, [step_file, other_file], downloads)
        current = "conversion"; step_conversion(page)
        current = "EXR download"; step_exr_download(page, downloads)
        current = "accessibility"; step_accessibility(page)
        errors = console_errors(browser.events)
        assert not errors, f"console errors: {errors}"
        check_key_use(browser.events)
        if big_part:
            current = "300-face part"; step_big_part_latency(page, big_part)
        else:
            log("SKIPPED the latency on a ~300-face part: ../shared/models/step/box_sides.STEP is absent")
        if assembly:
            current = "CAD views"; step_cad_views(page, assembly)
        else:
            log("SKIPPED the CAD views: no generated assembly given")
        if cube:
            current = "measure"; step_measure(page, cube, cylinder, MEASURE_SCREENSHOT)
            current = "section from face"; step_section_from_face(page, cube)
        else:
            log("SKIPPED measuring: no generated cube given")
        current = "stored files"; step_stored_files(page)
        current = "failed load"; step_failed_load(page, tmp)
        current = "problem+json"; step_problem_shown(page, tmp)
        current = "CSP"; step_csp_enforced(page)  # last: the refusal is logged as an error
        log("all steps passed")
        return 0
    except Exception:
        traceback.print_exc()
        shot = ARTIFACTS / f"failure-{current.replace(' ', '-')}.png"
        try:
            browser.screenshot(shot)
            log(f"step '{current}' failed; screenshot {shot}")
        except Exception as e:
            log(f"step '{current}' failed; no screenshot ({e})")
        failed = [json.dumps(e["params"]) for e in browser.events
                  if e["method"] == "Network.loadingFailed" and not e["params"].get("canceled")]
        (ARTIFACTS / "console.txt").write_text("\n".join(console_errors(browser.events) + failed) + "\n")
        return 1
    finally:
        browser.close()
        shutil.rmtree(tmp, ignore_errors=True)


if __name__ == "__main__":
    sys.exit(main())
