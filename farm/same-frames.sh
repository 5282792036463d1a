#!/usr/bin/env bash
# The farm checks' last step: renders the shot's camera path once
# (`pbgi render --camera-path`, 1 spp, into OUT/single/) and compares the
# first three frames a job stitched into OUT/job/frames/ with it, byte for
# byte. Exits 1, naming the frame, where one differs.
#
#   farm/same-frames.sh PBGI CAMERA_PATH OUT JOB-NAME
set -euo pipefail
pbgi=$1 path=$2 out=$3 job=$4
"$pbgi" render cornell-box --camera-path "$path" --spp 1 -o "$out/single/frame-{}.exr" > "$out/single.log"
for k in 0000 0001 0002; do
    if ! cmp "$out/job/frames/frame-$k.exr" "$out/single/frame-$k.exr"; then
        echo "frame $k: the $job's stitched frame differs from one render's (see $out)" >&2
        exit 1
    fi
done
