#!/usr/bin/env bash
# Builds the libFuzzer harnesses of fuzz/ (clang, AddressSanitizer and
# UndefinedBehaviorSanitizer) in build-fuzz and runs each for SECONDS_PER_TARGET
# seconds (default 600), each on one core, NURBSRT_FUZZ_JOBS of them at a time
# (default: one per core).
#   scripts/fuzz.sh [SECONDS_PER_TARGET]
# Environment: NURBSRT_FUZZ_BUILD_DIR (build-fuzz), NURBSRT_FUZZ_TARGETS (all),
# NURBSRT_FUZZ_JOBS (nproc).
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
JOBS=${NURBSRT_FUZZ_JOBS:-$(nproc)}
if ! [[ $JOBS =~ ^[1-9][0-9]*$ ]]; then
  echo "fuzz: NURBSRT_FUZZ_JOBS must be a positive integer" >&2
  exit 2
fi

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

# CPU seconds (user + system) of the finished children of the calling shell
# (`times` must run in that shell itself, not in a pipeline or a command
# substitution). $1: a scratch file.
child_cpu() {
  times > "$1"
  tail -n 1 "$1" |
    awk '{ s = 0; for (i = 1; i <= 2; i++) { split($i, p, /[ms]/); s += p[1] * 60 + p[2] } printf "%.0f", s }'
}

# Runs one target (in a subshell of its own, beside the others) and writes its
# summary line to $BUILD/logs/<target>.result, its findings to <target>.findings.
run_target() {
  local t=$1
  local bin="$BUILD/fuzz/fuzz_$t" corpus="$BUILD/corpus/$t" artifacts="$BUILD/artifacts/$t"
  local log="$BUILD/logs/$t.log" result="$BUILD/logs/$t.result" findings="$BUILD/logs/$t.findings"
  mkdir -p "$corpus" "$artifacts"
  rm -f "$result" "$findings"
  seed "$t" "$corpus"
  local dirs=("$corpus") d
  for d in "fuzz/seeds/$t" "fuzz/regressions/$t"; do [ -d "$d" ] && dirs+=("$d"); done
  local args=(-max_total_time="$SECONDS_PER_TARGET" -timeout=10 -rss_limit_mb=2048 -print_final_stats=1
        -artifact_prefix="$artifacts/")
  local dict
  dict=$(dict_of "$t")
  [ -n "$dict" ] && args+=(-dict="$dict")
  echo "== fuzz_$t: ${SECONDS_PER_TARGET} s, corpus $corpus"
  local start rc=0
  start=$(date +%s)
  "$bin" "${args[@]}" "${dirs[@]}" > "$log" 2>&1 || rc=$?
  local seconds=$(( $(date +%s) - start )) cpu runs units outcome=ok
  child_cpu "$BUILD/logs/$t.times" > "$BUILD/logs/$t.cpu"
  cpu=$(cat "$BUILD/logs/$t.cpu")
  runs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -n 1)
  runs=${runs:-0}
  units=$(find "$corpus" -type f | wc -l)
  if [ "$rc" -ne 0 ]; then
    outcome="FINDING"
    {
      echo "fuzz_$t: FINDING (exit $rc); log $log"
      grep -E "^==[0-9]+==ERROR|runtime error|unexpected exception|deadly signal|ALARM|out-of-memory|leak" "$log" | head -n 5 || true
      grep -o "Test unit written to .*" "$log" | sed 's/^Test unit written to /  reproducer: /' || true
      echo "  replay: $bin <reproducer>"
    } > "$findings"
  fi
  printf '%s %s %s %s %s %s\n' "$t" "$runs" "$seconds" "$cpu" "$units" "$outcome" > "$result"
}

mkdir -p "$BUILD/logs"
for t in "${TARGETS[@]}"; do
  while [ "$(jobs -rp | wc -l)" -ge "$JOBS" ]; do wait -n || true; done
  run_target "$t" &
done
wait

status=0
total_runs=0
total_cpu=0
total_seconds=0
summary=()
for t in "${TARGETS[@]}"; do
  if [ ! -s "$BUILD/logs/$t.result" ]; then
    echo "fuzz_$t: no result (the run did not finish)" >&2
    status=1
    continue
  fi
  read -r _ runs seconds cpu units outcome < "$BUILD/logs/$t.result"
  if [ "$outcome" != ok ]; then
    status=1
    cat "$BUILD/logs/$t.findings" >&2
  fi
  total_runs=$((total_runs + runs))
  total_seconds=$((total_seconds + seconds))
  total_cpu=$((total_cpu + cpu))
  summary+=("$(printf '%-16s %12s %8s %8s %10s %8s  %s' "$t" "$runs" "$seconds" "$cpu" "$((runs / (seconds > 0 ? seconds : 1)))" "$units" "$outcome")")
done

echo
printf '%-16s %12s %8s %8s %10s %8s  %s\n' target executions seconds "cpu s" "exec/s" corpus result
for line in "${summary[@]}"; do echo "$line"; done
printf '%-16s %12s %8s %8s  (%s at a time)\n' total "$total_runs" "$total_seconds" "$total_cpu" "$JOBS"
exit $status
