#!/usr/bin/env bash
# Runs farm/slurm/shot.sh on a one-node Slurm cluster on this machine
# (farm/slurm/one-node.sh: Debian's slurm-wlm and munge, as root) for three
# frames of the Cornell box's dolly path, 2 × 2 tiles each, and checks that
# its stitched frames are, byte for byte, the frames of one
# `pbgi render --camera-path`. CI's farm stage runs it; the cluster is
# stopped again unless KEEP_SLURM=1.
#
#   farm/slurm/check.sh [OUT]        (default target/farm-slurm)
set -euo pipefail
cd "$(dirname "$0")/../.."
out=$(realpath -m "${1:-target/farm-slurm}")
pbgi=$(realpath -m "${PBGI:-target/release/pbgi}")
[ -x "$pbgi" ] || cargo build --release
path=$PWD/docs/flicker/dolly.json
rm -rf "$out"
mkdir -p "$out"

farm/slurm/one-node.sh > "$out/one-node.log" 2>&1 || {
    cat "$out/one-node.log" >&2
    exit 1
}
[ "${KEEP_SLURM:-0}" = 1 ] || trap 'farm/slurm/one-node.sh stop > /dev/null 2>&1 || true' EXIT
sinfo --version
SECONDS=0
PBGI=$pbgi SCENE=cornell-box CAMERA_PATH=$path OUT=$out/job FRAMES=3 TILES=2,2 \
    timeout 300 farm/slurm/shot.sh --wait -- --spp 1 > "$out/shot.log" 2>&1 || {
    cat "$out/shot.log" >&2
    exit 1
}
job=$SECONDS
farm/same-frames.sh "$pbgi" "$path" "$out" "Slurm job"
echo "Slurm array: 1 bake, 12 tile tasks, 3 stitches in $job s; stitched frames identical to one render's, byte for byte"
