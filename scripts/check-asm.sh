#!/usr/bin/env bash
# Checks in the machine code that each kernel clone uses its instruction set:
# the AVX-512 clone zmm and mask (k) registers, the AVX2 clone ymm and no zmm,
# the portable clone neither. The clones are generic over the sink, so their
# instances are read from a binary that uses them (the cut_bench example).
set -euo pipefail
cd "$(dirname "$0")/.."

cargo build --release --example cut_bench --quiet
bin=target/release/examples/cut_bench
asm=target/cut_bench.asm
objdump -d --no-show-raw-insn -C "$bin" > "$asm"

# Body of every function whose name contains $1.
bodies() { awk -v pat="$1" '/^[0-9a-f]+ <.*>:$/ { p = index($0, pat) > 0 } p' "$asm"; }
count() { grep -cE "$1" || true; }

fail=0
check() { # name, pattern, op (gt0 | eq0)
    local n
    n=$(bodies "dispatch::$1::<" | count "$2")
    if { [ "$3" = gt0 ] && [ "$n" -gt 0 ]; } || { [ "$3" = eq0 ] && [ "$n" -eq 0 ]; }; then
        printf '  ok    %-13s %-22s %6s instructions\n' "$1" "$2" "$n"
    else
        printf '  FAIL  %-13s %-22s %6s instructions (expected %s)\n' "$1" "$2" "$n" "$3"
        fail=1
    fi
}

for clone in run_avx512 run_avx2 run_portable; do
    if [ "$(bodies "dispatch::$clone::<" | wc -l)" -lt 10 ]; then
        echo "  FAIL  no instance of $clone in $bin (inlined or renamed?)"
        fail=1
    fi
done
echo "kernel clones in $bin:"
check run_avx512 '%zmm' gt0
check run_avx512 '%k[1-7]' gt0
check run_avx2 '%ymm' gt0
check run_avx2 '%zmm' eq0
check run_portable '%ymm|%zmm' eq0
exit $fail
