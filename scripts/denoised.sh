#!/usr/bin/env bash
# Denoised path tracing beside pbgi, in one run: Mitsuba 3 + Intel OIDN and
# pbgi's own path tracer + OIDN (scripts/denoised.py), then `pbgi report`
# with those curves added.
#
#   scripts/denoised.sh SCENE [--xml MITSUBA.xml] [--spp 1,4,16,64,256]
#       [--resolution WxH] [--out DIR] [--repeat N] [-- PBGI-REPORT-ARGS...]
#
# e.g. the Cornell box (pbgi's built-in box and its Mitsuba export):
#   scripts/denoised.sh cornell-box --xml ../shared/scenes/cornell-box/cbox.xml \
#       --out report/cornell -- --reference refs/cornell-4096-s7.exr
#
# Everything after `--` goes to `pbgi report SCENE --out DIR --denoised
# DIR/denoised/denoised.csv`; without `--` only the denoised images are made.
# The first run makes a venv in target/denoise-venv (mitsuba 3.9.1, drjit,
# pyoidn, numpy from PyPI) and installs Debian's libllvm19 if Dr.Jit's LLVM
# backend is missing (as root); later runs reuse it.
set -euo pipefail
cd "$(dirname "$0")/.."

venv=target/denoise-venv
if [ ! -x "$venv/bin/python" ] || ! "$venv/bin/python" -c "import mitsuba, pyoidn" 2>/dev/null; then
    echo "making $venv (mitsuba, drjit, pyoidn, numpy)" >&2
    python3 -m venv "$venv"
    "$venv/bin/pip" install --quiet --upgrade pip
    "$venv/bin/pip" install --quiet "mitsuba==3.9.1" pyoidn numpy
fi
# Dr.Jit loads the newest libLLVM it finds. Debian's 15 loads, but cannot
# compile what Mitsuba asks of it (`fminimum`: the process aborts), so the
# check evaluates one.
llvm_works() {
    "$venv/bin/python" -c "import mitsuba as mi; mi.set_variant('llvm_ad_rgb'); import drjit as dr; print(dr.minimum(dr.llvm.Float([1, 2]), 1.5))" > /dev/null 2>&1
}
if ! llvm_works; then
    if [ "$(id -u)" = 0 ]; then
        apt-get install -y --no-install-recommends libllvm19 >&2
    else
        echo "Mitsuba's llvm_ad_rgb variant needs libLLVM 19: apt-get install libllvm19" >&2
        exit 1
    fi
    if ! llvm_works; then
        DRJIT_LIBLLVM_PATH=$(ls /usr/lib/*/libLLVM-19.so* 2> /dev/null | head -n 1)
        export DRJIT_LIBLLVM_PATH
        llvm_works || { echo "Dr.Jit's LLVM backend fails even with ${DRJIT_LIBLLVM_PATH:-no libLLVM 19}" >&2; exit 1; }
    fi
fi

[ -x target/release/pbgi ] || cargo build --release

scene=${1:?"usage: scripts/denoised.sh SCENE [--xml X.xml] [--spp ...] [--out DIR] [-- REPORT-ARGS]"}
shift
out=report
ours=()
while [ $# -gt 0 ] && [ "$1" != "--" ]; do
    case "$1" in
        --out) out=$2; shift 2 ;;
        *) ours+=("$1"); shift ;;
    esac
done
"$venv/bin/python" scripts/denoised.py "$scene" --out "$out/denoised" "${ours[@]}"
if [ "${1:-}" = "--" ]; then
    shift
    target/release/pbgi report "$scene" --out "$out" --denoised "$out/denoised/denoised.csv" "$@"
fi
