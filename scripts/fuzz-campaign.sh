#!/usr/bin/env bash
# The fuzz campaign: every cargo-fuzz target for at least RUNS executions
# (default 10^6), on JOBS processes (default: the cores), from the committed
# corpus and the regression inputs; then the corpus is minimised (`cargo fuzz
# cmin`) back into fuzz/corpus/TARGET, ready to commit. fuzz/regressions/TARGET
# (inputs that once failed, each named for its defect) is never minimised.
# CI's fuzz stage is the bounded smoke run on both (.ci/run).
#
#   scripts/fuzz-campaign.sh                 # all targets, 10^6 runs each
#   scripts/fuzz-campaign.sh 200000 2 microbuffer
#   FUZZ_SANITIZER=none scripts/fuzz-campaign.sh 1000000 2 microbuffer
#
# FUZZ_SANITIZER (default address) is cargo fuzz's `-s`: `none` runs the
# microbuffer target about 10x faster (its unsafe code is the dispatch and one
# bounds-checked-in-debug read; the 16-lane pipeline is safe code).
#
# A crash, a panic (a scheme, path or shading pipeline disagreeing is an
# assertion), more than 2 GB resident, a 1 GB allocation or a unit slower
# than FUZZ_TIMEOUT seconds (default 20) stops that target with its reproducer under fuzz/artifacts/TARGET;
# the script goes on with the others and exits non-zero at the end. Prints,
# and appends to target/fuzz-campaign.txt, executions, rate and corpus size.
set -euo pipefail
cd "$(dirname "$0")/.."
RUNS=${1:-1000000}
JOBS=${2:-$(nproc)}
SAN=${FUZZ_SANITIZER:-address}
# Seconds a unit may take: libFuzzer's clock is the wall's, so a campaign
# sharing the machine with builds needs more than CI's 20.
UNIT_TIMEOUT=${FUZZ_TIMEOUT:-20}
shift $(($# < 2 ? $# : 2))
TARGETS=("$@")
[ ${#TARGETS[@]} -gt 0 ] || TARGETS=(traversal scene_parsers microbuffer tree_file)
cargo fuzz --version > /dev/null 2>&1 || cargo install cargo-fuzz --locked

mkdir -p target
REPORT=target/fuzz-campaign.txt
WORK=$(mktemp -d)
trap 'rm -rf "$WORK"' EXIT
failed=""
echo "# $(date -u +%FT%TZ) $(git rev-parse --short HEAD 2>/dev/null || echo '?'), $RUNS runs a target on $JOBS job(s), sanitizer $SAN" | tee -a "$REPORT"
for target in "${TARGETS[@]}"; do
    corpus="$WORK/$target"
    mkdir -p "$corpus" "$WORK/logs-$target"
    cp -R "fuzz/corpus/$target/." "$corpus/"
    [ ! -d "fuzz/regressions/$target" ] || cp -R "fuzz/regressions/$target/." "$corpus/"
    before=$(find "fuzz/corpus/$target" -type f | wc -l)
    cargo fuzz build -O -s "$SAN" "$target"
    t0=$(date +%s)
    # Each job runs its share; libFuzzer writes job I's log to fuzz-I.log in
    # the working directory (the logs folder, via -jobs' relative paths).
    per=$(((RUNS + JOBS - 1) / JOBS))
    rc=0
    # (Outside the repository rust-toolchain.toml is not seen: name nightly.)
    (cd "$WORK/logs-$target" && cargo +nightly fuzz run --fuzz-dir "$OLDPWD/fuzz" -O -s "$SAN" "$target" "$corpus" -- \
        -runs="$per" -jobs="$JOBS" -workers="$JOBS" -rss_limit_mb=2048 -malloc_limit_mb=1024 \
        -timeout="$UNIT_TIMEOUT" -print_final_stats=1 -artifact_prefix="$OLDPWD/fuzz/artifacts/$target/" \
        > "$WORK/$target.log" 2>&1) || rc=$?
    s=$(($(date +%s) - t0))
    execs=$(cat "$WORK/logs-$target"/fuzz-*.log 2>/dev/null |
        awk '/^stat::number_of_executed_units:/ { n += $NF } END { print n + 0 }')
    rate=$(cat "$WORK/logs-$target"/fuzz-*.log 2>/dev/null |
        awk '/^stat::average_exec_per_sec:/ { n += $NF } END { print n + 0 }')
    if [ "$rc" -ne 0 ] || cat "$WORK/logs-$target"/fuzz-*.log 2>/dev/null |
        grep -qE 'ERROR: libFuzzer|panicked at|deadly signal'; then
        failed="$failed $target"
        echo "--- $target failed (exit $rc); the end of its logs:"
        tail -n 40 "$WORK/logs-$target"/fuzz-*.log "$WORK/$target.log" 2>/dev/null | grep -v '^"' || true
        continue
    fi
    # Minimise the grown corpus into the committed folder.
    mkdir -p "$WORK/min-$target"
    cargo fuzz cmin -O -s "$SAN" "$target" "$corpus" > "$WORK/cmin-$target.log" 2>&1 || {
        echo "cmin failed for $target:"
        tail -n 20 "$WORK/cmin-$target.log"
        failed="$failed $target(cmin)"
        continue
    }
    rm -rf "fuzz/corpus/$target"
    mkdir -p "fuzz/corpus/$target"
    cp -R "$corpus/." "fuzz/corpus/$target/"
    after=$(find "fuzz/corpus/$target" -type f | wc -l)
    line="$target: $execs executions in $s s ($rate/s on $JOBS job(s)); corpus $before -> $after units after cmin"
    echo "$line" | tee -a "$REPORT"
done
if [ -n "$failed" ]; then
    echo "failed:$failed (reproducers under fuzz/artifacts/)" | tee -a "$REPORT"
    exit 1
fi
