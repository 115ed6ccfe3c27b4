#!/usr/bin/env bash
# Builds the libFuzzer harnesses of fuzz/ (clang, AddressSanitizer and
# UndefinedBehaviorSanitizer) in build-fuzz and runs each for SECONDS_PER_TARGET
# seconds (default 600), one after another, on one core each.
#   scripts/fuzz.sh [SECONDS_PER_TARGET]
# Environment: NURBSRT_FUZZ_BUILD_DIR (build-fuzz), NURBSRT_FUZZ_TARGETS (all).
# The corpus of each target grows in BUILD/corpus/<target> from run to run; it
# starts from fuzz/seeds/<target>, fuzz/regressions/<target> (inputs that once
# crashed), and seeds made here: binary scenes from our own writer, the heads of
# the STEP/IGES samples of Debian's opencascade data and, when present, of
# ../shared/models. Exits non-zero when any target found a crash, a sanitizer
# error, an unexpected exception, a leak, a timeout (10 s) or ran out of memory
# (2 GB), and names the reproducer; prints executions per target and in total.
set -euo pipefail
cd "$(dirname "$0")/.."

SECONDS_PER_TARGET=${1:-600}
BUILD=${NURBSRT_FUZZ_BUILD_DIR:-build-fuzz}
read -r -a TARGETS <<< "${NURBSRT_FUZZ_TARGETS:-render_options job_spec multipart scene_file scene_binary prescan}"

if ! command -v clang++ >/dev/null; then
  echo "fuzz: clang++ is not installed (scripts/setup.sh installs it)" >&2
  exit 1
fi
if [ ! -f "$BUILD/build.ninja" ]; then
  CC=clang CXX=clang++ cmake -S . -B "$BUILD" -G Ninja -DNURBSRT_FUZZ=ON -DCMAKE_BUILD_TYPE=RelWithDebInfo
fi
cmake --build "$BUILD" --parallel "$(nproc)"

# The first KIB bytes of each file: the pre-scan's state is built from the start
# of a file, and short inputs keep the executions fast.
heads() {
  local out=$1 kib=$2; shift 2
  local f
  for f in "$@"; do
    [ -f "$f" ] || continue
    head -c $((kib * 1024)) "$f" > "$out/head-$(basename "$f")"
  done
}

seed() {
  local t=$1 corpus=$2
  case $t in
    scene_binary) "$BUILD/fuzz/nurbsrt_fuzz_seeds" "$corpus" ;;
    scene_file) cp docs/scenes/*.json "$corpus/" 2>/dev/null || true ;;
    prescan)
      shopt -s nullglob nocaseglob
      heads "$corpus" 8 /usr/share/opencascade/data/step/*.st*p /usr/share/opencascade/data/iges/*.ig*s \
        ../shared/models/*/*.st*p ../shared/models/*/*.ig*s
      shopt -u nullglob nocaseglob ;;
  esac
}

dict_of() {
  case $1 in
    render_options|job_spec|scene_file) echo fuzz/json.dict ;;
    multipart) echo fuzz/http.dict ;;
    prescan) echo fuzz/step.dict ;;
    scene_binary) echo fuzz/scene.dict ;;
  esac
}

# CPU seconds (user + system) used so far by the finished children of this
# shell: `times` must run in this shell itself, not in a command substitution.
child_cpu() {
  times > "$BUILD/logs/.times"
  tail -n 1 "$BUILD/logs/.times" |
    awk '{ s = 0; for (i = 1; i <= 2; i++) { split($i, p, /[ms]/); s += p[1] * 60 + p[2] } printf "%.0f", s }'
}

status=0
total_runs=0
total_cpu=0
total_seconds=0
summary=()
for t in "${TARGETS[@]}"; do
  bin="$BUILD/fuzz/fuzz_$t"
  corpus="$BUILD/corpus/$t"
  artifacts="$BUILD/artifacts/$t"
  log="$BUILD/logs/$t.log"
  mkdir -p "$corpus" "$artifacts" "$(dirname "$log")"
  seed "$t" "$corpus"
  dirs=("$corpus")
  for d in "fuzz/seeds/$t" "fuzz/regressions/$t"; do [ -d "$d" ] && dirs+=("$d"); done
  args=(-max_total_time="$SECONDS_PER_TARGET" -timeout=10 -rss_limit_mb=2048 -print_final_stats=1
        -artifact_prefix="$artifacts/")
  dict=$(dict_of "$t")
  [ -n "$dict" ] && args+=(-dict="$dict")
  echo "== fuzz_$t: ${SECONDS_PER_TARGET} s, corpus $corpus"
  start=$(date +%s)
  child_cpu > "$BUILD/logs/.cpu"
  cpu_start=$(cat "$BUILD/logs/.cpu")
  rc=0
  "$bin" "${args[@]}" "${dirs[@]}" > "$log" 2>&1 || rc=$?
  seconds=$(( $(date +%s) - start ))
  child_cpu > "$BUILD/logs/.cpu"
  cpu=$(( $(cat "$BUILD/logs/.cpu") - cpu_start ))
  runs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -n 1)
  runs=${runs:-0}
  units=$(find "$corpus" -type f | wc -l)
  if [ "$rc" -ne 0 ]; then
    status=1
    result="FINDING"
    echo "fuzz_$t: FINDING (exit $rc); log $log" >&2
    grep -E "^==[0-9]+==ERROR|runtime error|unexpected exception|deadly signal|ALARM|out-of-memory|leak" "$log" | head -n 5 >&2 || true
    grep -o "Test unit written to .*" "$log" | sed 's/^Test unit written to /  reproducer: /' >&2 || true
    echo "  replay: $bin <reproducer>" >&2
  else
    result="ok"
  fi
  total_runs=$((total_runs + runs))
  total_seconds=$((total_seconds + seconds))
  total_cpu=$((total_cpu + cpu))
  summary+=("$(printf '%-16s %12s %8s %8s %10s %8s  %s' "$t" "$runs" "$seconds" "$cpu" "$((runs / (seconds > 0 ? seconds : 1)))" "$units" "$result")")
done

echo
printf '%-16s %12s %8s %8s %10s %8s  %s\n' target executions seconds "cpu s" "exec/s" corpus result
for line in "${summary[@]}"; do echo "$line"; done
printf '%-16s %12s %8s %8s\n' total "$total_runs" "$total_seconds" "$total_cpu"
exit $status
