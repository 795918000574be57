#!/usr/bin/env bash
# The check a person with a GPU (or a lent machine) runs: what the GL is, whether the test suite
# holds on it, and what each pass of the five benchmark flythroughs costs at 1920x1080 under both cost profiles, timed by
# GPU timer queries where the GL has trustworthy ones. Everything lands in one folder, summed up
# in one report (report.md); docs/gpu.md says how to read it. Nothing here needs a GPU: on Mesa
# the same script runs and says which clock timed the passes.
#
#   scripts/gpu-check.sh [--out DIR] [--frames N] [--size WxH] [--scenes "a b"] [--no-tests]
#
#   --out DIR     where the report and its files go (default: gpu-check-<date>)
#   --frames N    measured frames per configuration and scene (default: 300)
#   --size WxH    frame size (default: 1920x1080)
#   --scenes LIST the benchmark scenes (default: the five in assets/scenes)
#   --no-tests    skip the test suite (e.g. for a quick look at the timings)
set -uo pipefail
cd "$(dirname "$0")/.."

out="gpu-check-$(date +%Y%m%d-%H%M%S)"
frames=300
size=1920x1080
scenes="q3dm6ish oa_dm1 oa_dm3 ctf_compromise wrackdm17"
tests=1
while [ $# -gt 0 ]; do
    case "$1" in
        --out) out="$2"; shift 2 ;;
        --frames) frames="$2"; shift 2 ;;
        --size) size="$2"; shift 2 ;;
        --scenes) scenes="$2"; shift 2 ;;
        --no-tests) tests=0; shift ;;
        -h|--help) sed -n 2,15p "$0"; exit 0 ;;
        *) echo "error: unknown argument $1 (see --help)" >&2; exit 2 ;;
    esac
done
mkdir -p "$out"
log() { echo "[$(date +%H:%M:%S)] $*"; }

log "building (release)"
cargo build --release 2>&1 | tail -1
bin=target/release/shadowlab
[ -x "$bin" ] || { echo "error: the build failed" >&2; exit 1; }
log "fetching OpenArena's data (once)"
scripts/fetch-openarena.sh | tail -1

log "info"
"$bin" info --json > "$out/info.json" 2> "$out/info.err" || { cat "$out/info.err" >&2; exit 1; }
"$bin" info > "$out/info.txt" 2>&1
command -v nvidia-smi >/dev/null && nvidia-smi > "$out/nvidia-smi.txt" 2>&1
{ git rev-parse HEAD; git status --short | head -20; } > "$out/commit.txt" 2>/dev/null

if [ "$tests" = 1 ]; then
    log "test suite (cargo test --release --no-fail-fast): $out/tests.log"
    start=$(date +%s)
    cargo test --release --no-fail-fast > "$out/tests.log" 2>&1
    echo "$? $(( $(date +%s) - start ))" > "$out/tests.status"
fi

for scene in $scenes; do
    log "bench $scene at $size, $frames frames per technique"
    "$bin" bench --scene "assets/scenes/$scene.toml" --size "$size" --frames "$frames" \
        --sweep technique=none,shadow_map,shadow_volume,subdivision \
        --sweep plan.profile=software,gpu \
        --json "$out/bench-$scene.json" > "$out/bench-$scene.txt" 2>&1 \
        || log "bench $scene failed: $out/bench-$scene.txt"
done

python3 scripts/gpu-report.py "$out" > "$out/report.md"
log "report: $out/report.md"
