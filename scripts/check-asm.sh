#!/usr/bin/env bash
# Checks in the machine code that each clone uses its instruction set.
#
#   scripts/check-asm.sh            x86-64: builds the pbgi binary and checks the
#                                   AVX-512 clones (zmm and mask k registers), the
#                                   AVX2 clones (ymm, no zmm), the portable ones
#                                   (neither)
#   scripts/check-asm.sh aarch64    the NEON clones (NEON .4s vector arithmetic) in
#                                   target/arm/.../pbgi, built by the ARM stage of
#                                   .ci/run (not built here)
#
# Three kernels, each compiled once per instruction set by the one dispatch
# point, src/simd/dispatch.rs ({avx512,avx2,neon,portable}::<Kernel>):
#   traversal       cut::run::Run (generic over the sink: every instance the
#                   binary holds is checked)
#   shading         microbuffer::shade::ShadePacket (the 16-lane splatting and
#                   convolution)
#   scalar-shading  microbuffer::shade::ShadeCuts (the scalar pipeline, which
#                   must not call out either)
# Everything a clone runs is inlined into it; a pbgi function it *calls*
# instead is compiled for the baseline target (SSE2), whatever the clone's
# features (TOOLCHAIN.md: measured 12x slower), so such calls fail the check,
# by name.
set -euo pipefail
cd "$(dirname "$0")/.."

arch=${1:-x86_64}
case "$arch" in
x86_64)
    cargo build --release --bin pbgi --quiet
    bin=target/release/pbgi
    asm=target/pbgi.asm
    objdump -d --no-show-raw-insn -C "$bin" > "$asm"
    isas="avx512 avx2 portable"
    ;;
aarch64)
    bin=target/arm/aarch64-unknown-linux-gnu/release/pbgi
    [ -f "$bin" ] || { echo "FAIL  $bin not built (run the ARM stage of .ci/run first)"; exit 1; }
    asm=target/arm/pbgi.asm
    aarch64-linux-gnu-objdump -d --no-show-raw-insn -C "$bin" > "$asm"
    isas="neon portable"
    ;;
*)
    echo "usage: $0 [x86_64|aarch64]" >&2
    exit 2
    ;;
esac

# The symbol of clone `family` for `isa`, as it appears in the disassembly.
symbol() {
    case "$1" in
    traversal) echo "dispatch::$2::<pbgi::cut::run::Run<" ;;
    shading) echo "dispatch::$2::<pbgi::microbuffer::shade::ShadePacket>" ;;
    scalar-shading) echo "dispatch::$2::<pbgi::microbuffer::shade::ShadeCuts>" ;;
    esac
}

# Bodies of every function whose name contains $1.
bodies() { awk -v pat="$1" '/^[0-9a-f]+ <.*>:$/ { p = index($0, pat) > 0 } p' "$asm"; }
count() { grep -cE "$1" || true; }

fail=0
check() { # symbol, label, pattern, op (gt0 | eq0), what
    local n
    n=$(bodies "$1" | count "$3")
    if { [ "$4" = gt0 ] && [ "$n" -gt 0 ]; } || { [ "$4" = eq0 ] && [ "$n" -eq 0 ]; }; then
        printf '  ok    %-24s %-34s %6s instructions\n' "$2" "$5" "$n"
    else
        printf '  FAIL  %-24s %-34s %6s instructions (expected %s)\n' "$2" "$5" "$n" "${4/gt0/> 0}"
        fail=1
    fi
}

# Out-of-line pbgi code called from a clone runs on the baseline target.
calls() { # symbol, label
    local callees
    callees=$(bodies "$1" |
        sed -nE 's/.*\s(call|bl)q?\s+[0-9a-f]+ <(.*)>$/\2/p' | grep 'pbgi::' | grep -vF "$1" |
        sort | uniq -c | sort -rn || true)
    if [ -z "$callees" ]; then
        printf '  ok    %-24s %-34s\n' "$2" 'calls no out-of-line pbgi code'
    else
        printf '  FAIL  %-24s %s\n' "$2" 'calls out-of-line pbgi code, compiled for the baseline target:'
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
}

echo "clones in $bin:"
for family in traversal shading scalar-shading; do
    for isa in $isas; do
        sym=$(symbol "$family" "$isa")
        label="$family $isa"
        n=$(bodies "$sym" | grep -c '^[0-9a-f]* <' || true)
        lines=$(bodies "$sym" | wc -l)
        if [ "$lines" -lt 10 ] && [ "$arch" = aarch64 ] && [ "$family" = scalar-shading ] && [ "$isa" = neon ]; then
            # NEON is aarch64's baseline: the scalar pipeline's NEON clone is
            # the portable one instruction for instruction, and LLVM merges
            # identical functions.
            echo "  ok    $label      merged with the portable clone (NEON is the aarch64 baseline)"
            continue
        fi
        if [ "$lines" -lt 10 ]; then
            echo "  FAIL  no instance of $sym in $bin (inlined or renamed?)"
            fail=1
            continue
        fi
        printf '  %-30s %d instance(s), %d instructions\n' "$label" "$n" "$lines"
        case "$isa" in
        avx512)
            # The scalar pipeline has no vectors to speak of; the others must use zmm and k.
            if [ "$family" != scalar-shading ]; then
                check "$sym" "$label" '%zmm' gt0 'uses zmm'
                check "$sym" "$label" '%k[1-7]' gt0 'uses mask registers k1-k7'
            fi
            ;;
        avx2)
            [ "$family" != scalar-shading ] && check "$sym" "$label" '%ymm' gt0 'uses ymm'
            check "$sym" "$label" '%zmm' eq0 'no zmm'
            check "$sym" "$label" '%k[0-7]' eq0 'no mask registers'
            ;;
        neon)
            # fmla/fmul/fadd/fcm* on v registers arranged as four f32 lanes.
            [ "$family" != scalar-shading ] && check "$sym" "$label" '\sf[a-z]+\s+v[0-9]+\.4s' gt0 'NEON f32x4 arithmetic (v.4s)'
            check "$sym" "$label" '\sz[0-9]+\.|\sp[0-9]+\.' eq0 'no SVE registers'
            ;;
        portable)
            [ "$arch" = x86_64 ] && check "$sym" "$label" '%ymm|%zmm' eq0 'no ymm or zmm'
            ;;
        esac
        [ "$isa" != portable ] && calls "$sym" "$label"
    done
done

[ "$fail" -eq 0 ] && echo "check-asm: all clones use their instruction set" || echo "check-asm: FAILED"
exit $fail
