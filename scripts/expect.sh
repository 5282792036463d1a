#!/usr/bin/env bash
# The README's table of what to expect (docs/expect.md, copied into
# README.md's marked block): one `pbgi report` per scene, beside Mitsuba 3 +
# Intel OIDN rendered just before it (scripts/denoised.sh), all in one run.
#
#   scripts/expect.sh REFS [OUT]
#
# REFS holds two converged references of each scene, seeds 7 and 8 (their
# mean is the reference, their difference its own noise):
#   cornell-box-{7,8}.exr     pbgi reference cornell-box --spp 4096 --seed S
#   cb720-{7,8}.exr           … cornell-box --resolution 1280x720 --spp 1024
#   sunlit-room-{7,8}.exr     … scenes/sunlit-room.xml --spp 4096
#   sunlit-atrium-{7,8}.exr   … scenes/sunlit-atrium.xml --spp 4096
#   nave-{7,8}.exr            … nave --spp 2048
# OUT (default target/expect) keeps each scene's report. Takes about 20
# minutes on two cores; run it on an otherwise idle machine, as the seconds
# are the table. tests/readme.rs fails while the README's block differs from
# docs/expect.md, or the Cornell box's default image is no longer the one
# the table measured.
set -euo pipefail
cd "$(dirname "$0")/.."

refs=${1:?"usage: scripts/expect.sh REFS [OUT]"}
out=${2:-target/expect}
mkdir -p "$out"
targets=5,3,2,1.5,1
# One curve, the defaults, as their camera samples rise (and through OIDN).
common=(--targets "$targets" --gathers cache --spp 1,2,4,8,16 --path-tracer-spp 16)

denoise=()
if [ -n "${OIDN_DIR:-}" ]; then
    cargo build --release --quiet --features denoise
    denoise=(--denoise)
else
    echo "OIDN_DIR unset: no pbgi + OIDN column (export OIDN_DIR=\$(scripts/oidn.sh))" >&2
    cargo build --release --quiet
fi

# scene title mitsuba-xml resolution refs-stem
runs=(
    "cornell-box|Cornell box, 256²|../shared/scenes/cornell-box/cbox.xml||cornell-box"
    "cornell-box|Cornell box, 1280 × 720|../shared/scenes/cornell-box/cbox.xml|1280x720|cb720"
    "scenes/sunlit-room.xml|sunlit room|scenes/sunlit-room.xml||sunlit-room"
    "scenes/sunlit-atrium.xml|sunlit atrium|scenes/sunlit-atrium.xml||sunlit-atrium"
    "nave|nave (no Mitsuba file)|||nave"
)
rows=()
for run in "${runs[@]}"; do
    IFS='|' read -r scene title xml resolution stem <<< "$run"
    dir="$out/$stem"
    size=()
    [ -n "$resolution" ] && size=(--resolution "$resolution")
    report=(--title "$title" --reference "$refs/$stem-7.exr" --reference "$refs/$stem-8.exr"
        "${size[@]}" "${common[@]}" "${denoise[@]}")
    echo "== $title" >&2
    if [ -n "$xml" ]; then
        scripts/denoised.sh "$scene" --xml "$xml" "${size[@]}" --spp 1,4,16,64,256 --no-pbgi \
            --out "$dir" -- "${report[@]}" > "$dir.log"
    else
        mkdir -p "$dir"
        target/release/pbgi report "$scene" --out "$dir" "${report[@]}" > "$dir.log"
    fi
    rows+=("$(tail -n 1 "$dir/summary.md")")
done

digest=$(awk 'NF == 2 && $2 == "cornell-box" { print $1 }' docs/image-digests.txt)
{
    echo "One run per scene, $(nproc) threads, $(date -u +%Y-%m-%d) (\`scripts/expect.sh\`; the box's default"
    echo "image digest $digest). pbgi at its defaults as the camera samples rise (1–16 spp),"
    echo "alone and through OIDN, and Mitsuba 3 + OIDN (1–256 spp) just before it; relative RMSE"
    echo "against converged references (4096-spp path traces; 2048 for the nave, 1024 at 720p):"
    echo
    head -n 2 "$out/cornell-box/summary.md"
    printf '%s\n' "${rows[@]}"
    echo
    echo "\`~\`: extrapolated; \`—\`: not reached; n/a: not measured."
} > docs/expect.md

# README.md's block between the markers becomes docs/expect.md.
python3 - <<'EOF'
import re
readme = open("README.md").read()
table = open("docs/expect.md").read()
begin, end = "<!-- begin docs/expect.md -->\n", "<!-- end docs/expect.md -->"
i, j = readme.index(begin) + len(begin), readme.index(end)
open("README.md", "w").write(readme[:i] + table + readme[j:])
EOF
echo "wrote docs/expect.md and README.md's table" >&2
