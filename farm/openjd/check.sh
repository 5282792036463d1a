#!/usr/bin/env bash
# Runs the OpenJD job (farm/openjd/shot.yaml) with openjd-cli from PyPI on
# a short camera path of the Cornell box, 2 × 2 tiles a frame, and checks
# that its stitched frames are, byte for byte, the frames of one
# `pbgi render --camera-path`. CI's farm stage runs it.
#
#   farm/openjd/check.sh [OUT]        (default target/farm-openjd)
#
# PBGI names the binary (default target/release/pbgi, built if missing).
set -euo pipefail
cd "$(dirname "$0")/../.."
out=$(realpath -m "${1:-target/farm-openjd}")
pbgi=$(realpath -m "${PBGI:-target/release/pbgi}")
[ -x "$pbgi" ] || cargo build --release
py=$PWD/target/openjd-py
if ! PYTHONPATH=$py python3 -c "import openjd.cli" 2> /dev/null; then
    echo "installing openjd-cli from PyPI into $py" >&2
    python3 -m pip install --quiet --target "$py" openjd-cli >&2
fi
openjd() { PYTHONPATH=$py python3 -m openjd "$@"; }

path=$PWD/docs/flicker/dolly.json
frames=0-2
rm -rf "$out"
mkdir -p "$out"
openjd check farm/openjd/shot.yaml
SECONDS=0
openjd run farm/openjd/shot.yaml --step Stitch --run-dependencies \
    -p Pbgi="$pbgi" -p Scene=cornell-box -p CameraPath="$path" -p OutDir="$out/job" \
    -p Frames="$frames" -p Tiles=2,2 -p TileNumbers=0-3 -p Spp=1 > "$out/openjd.log" || {
    tail -n 40 "$out/openjd.log" >&2
    echo "the OpenJD job failed (its log: $out/openjd.log)" >&2
    exit 1
}
job=$SECONDS
farm/same-frames.sh "$pbgi" "$path" "$out" "OpenJD job"
echo "OpenJD job: 3 frames × 4 tiles from one bake in $job s; stitched frames identical to one render's, byte for byte"
