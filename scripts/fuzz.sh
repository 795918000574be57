#!/usr/bin/env bash
# Runs every fuzz target for SECONDS and prints, per target, the executions (libFuzzer's final
# stats), the corpus size and the findings (crash, oom, timeout and leak files it wrote).
# JOBS (default 1) targets run at once. Exits non-zero when any target found something.
#
#   scripts/fuzz-corpus.sh          # seed corpora from the fetched data (once)
#   scripts/fuzz.sh 600             # every target 10 minutes, one at a time
#   JOBS=2 scripts/fuzz.sh 600      # two at a time
set -euo pipefail
secs=${1:-}
if ! [[ $secs =~ ^[0-9]+$ ]] || [ "$secs" -eq 0 ]; then
    echo "usage: [JOBS=N] scripts/fuzz.sh SECONDS" >&2
    exit 2
fi
jobs=${JOBS:-1}
root=$(cd "$(dirname "$0")/.." && pwd)
if ! cargo fuzz --version >/dev/null 2>&1; then
    echo "error: cargo-fuzz is missing; install it with: cargo install cargo-fuzz" >&2
    exit 2
fi
if ! cargo +nightly --version >/dev/null 2>&1; then
    echo "error: the nightly toolchain is missing (the sanitizer flags need it);" \
        "install it with: rustup toolchain install nightly" >&2
    exit 2
fi
cd "$root/fuzz"
targets=$(cargo +nightly fuzz list)
echo "building $(echo "$targets" | wc -l) targets..." >&2
cargo +nightly fuzz build >&2
logs=$root/fuzz/logs
mkdir -p "$logs"
stamp=$logs/.start
touch "$stamp"

run_one() {
    local t=$1
    mkdir -p "corpus/$t" "artifacts/$t"
    # -timeout: an input slower than 10 s is a finding (a hang), not a stall of the whole run.
    # The outer timeout only guards against a fuzzer that never stops.
    timeout $((secs + 300)) cargo +nightly fuzz run "$t" "corpus/$t" -- \
        -max_total_time="$secs" -print_final_stats=1 -timeout=10 -rss_limit_mb=2048 \
        >"$logs/$t.log" 2>&1 || true
}

running=0
for t in $targets; do
    if [ "$running" -ge "$jobs" ]; then
        wait -n || true
        running=$((running - 1))
    fi
    echo "fuzzing $t for ${secs}s..." >&2
    run_one "$t" &
    running=$((running + 1))
done
wait

total=0
printf '%-14s %8s %14s %8s %9s\n' target seconds executions corpus findings
for t in $targets; do
    log=$logs/$t.log
    execs=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$log" | grep -o '[0-9]*$' | tail -1 || true)
    if [ -z "$execs" ]; then
        # No final stats (killed): the last status line's count.
        execs=$(grep -o '^#[0-9]*' "$log" | tail -1 | tr -d '#' || true)
    fi
    corpus=$(find "corpus/$t" -type f | wc -l)
    found=$(find "artifacts/$t" -type f -newer "$stamp" \
        \( -name 'crash-*' -o -name 'oom-*' -o -name 'timeout-*' -o -name 'leak-*' \) | wc -l)
    total=$((total + found))
    printf '%-14s %8s %14s %8s %9s\n' "$t" "$secs" "${execs:-?}" "$corpus" "$found"
done
if [ "$total" -gt 0 ]; then
    echo "findings (logs in fuzz/logs/):" >&2
    find artifacts -type f -newer "$stamp" \
        \( -name 'crash-*' -o -name 'oom-*' -o -name 'timeout-*' -o -name 'leak-*' \) >&2
    exit 1
fi
