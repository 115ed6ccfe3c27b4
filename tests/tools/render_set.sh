#!/usr/bin/env bash
# Renders a fixed set of scenes (the README's, and 8 models x 2 views x plain /
# anti-aliased with edges / shadows) with their AOVs and statistics into OUTDIR,
# the statistics without their timings. Run it before and after a change that
# must not change what is drawn, then: diff -r BEFORE AFTER (byte for byte).
#   tests/tools/render_set.sh build/nurbsrt /tmp/before [MODELS_DIR]
set -euo pipefail
bin=$1 out=$2
models=${3:-$(cd "$(dirname "$0")/../../.." && pwd)/shared/models}
root=$(cd "$(dirname "$0")/../.." && pwd)
mkdir -p "$out"
if [[ ! -d $models ]]; then echo "render_set: $models absent, README models skipped" >&2; fi

render() {  # name, then render arguments
    local name=$1; shift
    "$bin" render "$@" -o "$out/$name.png" --aov "$out/$name.exr" --stats "$out/$name.stats.full.json" -q
    # Timings differ run to run; everything else must not.
    python3 - "$out/$name.stats.full.json" "$out/$name.stats.json" <<'PY'
import json, sys
def strip(x):
    if isinstance(x, dict):
        return {k: strip(v) for k, v in x.items() if not (k.endswith("_ms") or k in ("timings", "stages"))}
    if isinstance(x, list):
        return [strip(v) for v in x]
    return x
json.dump(strip(json.load(open(sys.argv[1]))), open(sys.argv[2], "w"), indent=1, sort_keys=True)
PY
    rm "$out/$name.stats.full.json"
    # OpenEXR stamps the file with the time it was written (capDate): blank it.
    python3 - "$out/$name.exr" <<'PY'
import sys
p = sys.argv[1]
b = bytearray(open(p, "rb").read())
key = b"capDate\0string\0"
i = b.find(key)
if i >= 0:
    n = int.from_bytes(b[i + len(key):i + len(key) + 4], "little")
    start = i + len(key) + 4
    b[start:start + n] = b"0" * n
open(p, "wb").write(bytes(b))
PY
}

size=(--width 320 --height 240)
render readme_ducks "$root/docs/scenes/27_ducks.json" "${size[@]}" --background 1,1,1 --edges
if [[ -d $models ]]; then
    render readme_cornetta "$models/step/bug27693_cornetta-step.stp" "${size[@]}" --background 1,1,1 --edges
    render readme_trj8 "$models/step/trj8_b1-ec-214.stp" "${size[@]}" --background 1,1,1 --edges
    render readme_as1_shadows "$models/step/as1-oc-214.stp" "${size[@]}" --background 1,1,1 --edges --shadows
    for m in step/screw.step step/linkrods.step step/bug24283_spheres.stp step/featuretype.STEP \
             iges/bearing.iges iges/hammer.iges iges/torus.igs iges/OCC8842_cone_CATIA.igs; do
        n=$(basename "${m%.*}")
        for view in iso top; do
            render "${n}_${view}_plain" "$models/$m" "${size[@]}" --view "$view" --antialias 0
            render "${n}_${view}_aa_edges" "$models/$m" "${size[@]}" --view "$view" --antialias 4 --edges
            render "${n}_${view}_shadows" "$models/$m" "${size[@]}" --view "$view" --shadows
        done
    done
fi
echo "render_set: $(ls "$out"/*.png | wc -l) scenes in $out"
