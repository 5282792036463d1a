#!/usr/bin/env bash
# Checks in the machine code that each kernel clone uses its instruction set.
#
#   scripts/check-asm.sh            x86-64: builds the cut_bench example and checks
#                                   the AVX-512 clone (zmm and mask k registers), the
#                                   AVX2 clone (ymm, no zmm), the portable clone
#                                   (neither)
#   scripts/check-asm.sh aarch64    the NEON clone (NEON .4s vector arithmetic) in
#                                   target/arm/.../cut_bench, built by the ARM stage
#                                   of .ci/run (not built here)
#
# The clones (run_avx512, run_avx2, run_neon, run_portable in src/cut/dispatch.rs)
# are generic over the sink, so their instances are read from a binary that uses
# them: the cut_bench example. Every kernel (scalar, single, packet, hybrid) is
# inlined into each clone; a pbgi function the clone *calls* instead is compiled
# for the baseline target (SSE2), whatever the clone's features (TOOLCHAIN.md:
# measured 12x slower), so such calls fail the check too, by name.
set -euo pipefail
cd "$(dirname "$0")/.."

arch=${1:-x86_64}
case "$arch" in
x86_64)
    cargo build --release --example cut_bench --quiet
    bin=target/release/examples/cut_bench
    asm=target/cut_bench.asm
    objdump -d --no-show-raw-insn -C "$bin" > "$asm"
    clones="run_avx512 run_avx2 run_portable"
    simd_clones="run_avx512 run_avx2"
    ;;
aarch64)
    bin=target/arm/aarch64-unknown-linux-gnu/release/examples/cut_bench
    [ -f "$bin" ] || { echo "FAIL  $bin not built (run the ARM stage of .ci/run first)"; exit 1; }
    asm=target/arm/cut_bench.asm
    aarch64-linux-gnu-objdump -d --no-show-raw-insn -C "$bin" > "$asm"
    clones="run_neon run_portable"
    simd_clones="run_neon"
    ;;
*)
    echo "usage: $0 [x86_64|aarch64]" >&2
    exit 2
    ;;
esac

# Bodies of every function whose name contains $1.
bodies() { awk -v pat="$1" '/^[0-9a-f]+ <.*>:$/ { p = index($0, pat) > 0 } p' "$asm"; }
count() { grep -cE "$1" || true; }

fail=0
check() { # clone, pattern, op (gt0 | eq0), what
    local n
    n=$(bodies "dispatch::$1::<" | count "$2")
    if { [ "$3" = gt0 ] && [ "$n" -gt 0 ]; } || { [ "$3" = eq0 ] && [ "$n" -eq 0 ]; }; then
        printf '  ok    %-13s %-34s %6s instructions\n' "$1" "$4" "$n"
    else
        printf '  FAIL  %-13s %-34s %6s instructions (expected %s)\n' "$1" "$4" "$n" "${3/gt0/> 0}"
        fail=1
    fi
}

echo "kernel clones in $bin:"
for clone in $clones; do
    n=$(bodies "dispatch::$clone::<" | grep -c '^[0-9a-f]* <' || true)
    lines=$(bodies "dispatch::$clone::<" | wc -l)
    if [ "$lines" -lt 10 ]; then
        echo "  FAIL  no instance of $clone in $bin (inlined or renamed?)"
        fail=1
    else
        printf '  %-19s %d instance(s), %d instructions\n' "$clone" "$n" "$lines"
    fi
done

case "$arch" in
x86_64)
    check run_avx512 '%zmm' gt0 'uses zmm'
    check run_avx512 '%k[1-7]' gt0 'uses mask registers k1-k7'
    check run_avx2 '%ymm' gt0 'uses ymm'
    check run_avx2 '%zmm' eq0 'no zmm'
    check run_avx2 '%k[0-7]' eq0 'no mask registers'
    check run_portable '%ymm|%zmm' eq0 'no ymm or zmm'
    ;;
aarch64)
    # fmla/fmul/fadd/fcm* on v registers arranged as four f32 lanes.
    check run_neon '\sf[a-z]+\s+v[0-9]+\.4s' gt0 'NEON f32x4 arithmetic (v.4s)'
    check run_neon '\sz[0-9]+\.|\sp[0-9]+\.' eq0 'no SVE registers'
    ;;
esac

# Out-of-line pbgi code called from a SIMD clone runs on the baseline target.
for clone in $simd_clones; do
    callees=$(bodies "dispatch::$clone::<" |
        sed -nE 's/.*\s(call|bl)q?\s+[0-9a-f]+ <(.*)>$/\2/p' | grep 'pbgi::' | grep -v "dispatch::$clone::<" |
        sort | uniq -c | sort -rn || true)
    if [ -z "$callees" ]; then
        printf '  ok    %-13s %-34s\n' "$clone" 'calls no out-of-line pbgi code'
    else
        printf '  FAIL  %-13s %s\n' "$clone" 'calls out-of-line pbgi code, compiled for the baseline target:'
        while read -r n name; do
            b=$(awk -v pat="<$name>:" '/^[0-9a-f]+ <.*>:$/ { p = index($0, pat) > 0 } p' "$asm")
            printf '          %3d call site(s): %s\n' "$n" "$name"
            printf '                            (%d instructions; %d xmm, %d ymm, %d zmm)\n' \
                "$(printf '%s\n' "$b" | wc -l)" "$(printf '%s\n' "$b" | count '%xmm')" \
                "$(printf '%s\n' "$b" | count '%ymm')" "$(printf '%s\n' "$b" | count '%zmm')"
        done <<< "$callees"
        echo "          make it #[inline(always)] (a closure too) or #[multiversion::inherit_target]"
        fail=1
    fi
done

[ "$fail" -eq 0 ] && echo "check-asm: all clones use their instruction set" || echo "check-asm: FAILED"
exit $fail
