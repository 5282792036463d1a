#!/usr/bin/env bash
# Renders every built-in scene in a few modes and prints the image digest of
# each (`pbgi render` prints it: a hash of every pixel's bits, the same for
# every scheme, instruction set and thread count). `--check` compares with
# docs/image-digests.txt: a change meant to move no pixel (a refactoring)
# leaves every line as it is; one that changes images updates the file in
# the same commit and says why.
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release --quiet --bin pbgi
PBGI=${CARGO_TARGET_DIR:-target}/release/pbgi
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
cases=(
    "cornell-box"
    "cornell-box --direct sampled"
    "cornell-box --gathers all"
    "cornell-box --gathers sparse"
    "cornell-box --gathers cache:0.1"
    "cornell-box --ao --spp 1"
    "cornell-box --bounces 2 --spp 1"
    "cornell-box --tree-precision full"
    "cornell-box --scheme scalar --spp 1"
    "cornell-box --scheme hybrid --spp 1"
    "cornell-box-glossy --spp 1"
    "cornell-box-glossy --gathers sparse --spp 1"
    "nave --spp 1"
)
out="$tmp/digests.txt"
for c in "${cases[@]}"; do
    # shellcheck disable=SC2086
    d=$("$PBGI" render $c -o "$tmp/img.exr" 2> /dev/null | sed -n 's/.*image digest \([0-9a-f]*\).*/\1/p')
    printf '%s  %s\n' "${d:?no digest printed for $c}" "$c" >> "$out"
done
if [ "${1:-}" = "--check" ]; then
    diff -u docs/image-digests.txt "$out" && echo "image digests: all ${#cases[@]} unchanged"
else
    cat "$out"
fi
