#!/usr/bin/env bash
# Submit one pbgi shot to Slurm: bake once, render frames x tiles as an array,
# stitch each frame. Chained with --dependency=afterok.
#
#   farm/slurm/shot.sh [--pbgi P] [--scene S] [--camera-path J] [--out DIR]
#                      [--frames N] [--tiles C,R] [--cpus-per-task K]
#                      [--wait] [-- EXTRA RENDER FLAGS...]
# Every flag also reads an environment variable: PBGI, SCENE, CAMERA_PATH,
# OUT, FRAMES, TILES, CPUS_PER_TASK, WAIT=1, RENDER_FLAGS (word-split),
# SETTINGS (word-split, for both bake and render: what the tree fixes, e.g.
# "--density 2000 --bounces 2"), and SBATCH_ARGS (word-split, added to all three sbatch calls, e.g.
# "--partition=gpu --time=2:00:00").
# OUT must be a directory every node sees. Prints the three job ids; with
# --wait, waits for all of them and exits 1 if any task did not succeed.
set -euo pipefail

die() { echo "shot.sh: $*" >&2; exit 2; }

PBGI=${PBGI:-pbgi}
SCENE=${SCENE:-}
CAMERA_PATH=${CAMERA_PATH:-}
OUT=${OUT:-}
FRAMES=${FRAMES:-1}
TILES=${TILES:-1,1}
CPUS_PER_TASK=${CPUS_PER_TASK:-1}
WAIT=${WAIT:-0}
read -r -a EXTRA <<< "${RENDER_FLAGS:-}"
read -r -a SETTINGS <<< "${SETTINGS:-}"
read -r -a SB_ARGS <<< "${SBATCH_ARGS:-}"

while [ $# -gt 0 ]; do
    case "$1" in
        --pbgi) PBGI=$2; shift 2 ;;
        --scene) SCENE=$2; shift 2 ;;
        --camera-path) CAMERA_PATH=$2; shift 2 ;;
        --out) OUT=$2; shift 2 ;;
        --frames) FRAMES=$2; shift 2 ;;
        --tiles) TILES=$2; shift 2 ;;
        --cpus-per-task) CPUS_PER_TASK=$2; shift 2 ;;
        --wait) WAIT=1; shift ;;
        --) shift; EXTRA+=("$@"); break ;;
        -h|--help) sed -n '2,14p' "$0"; exit 0 ;;
        *) die "unknown argument '$1' (render flags go after --)" ;;
    esac
done

[ -n "$SCENE" ] || die "SCENE / --scene is required"
[ -n "$CAMERA_PATH" ] || die "CAMERA_PATH / --camera-path is required"
[ -n "$OUT" ] || die "OUT / --out is required"
[[ "$FRAMES" =~ ^[1-9][0-9]*$ ]] || die "FRAMES must be a positive integer, got '$FRAMES'"
[[ "$TILES" =~ ^([1-9][0-9]*),([1-9][0-9]*)$ ]] || die "TILES must be C,R, got '$TILES'"
COLS=${BASH_REMATCH[1]} ROWS=${BASH_REMATCH[2]}
TPF=$((COLS * ROWS))                  # tiles per frame
NTASKS=$((FRAMES * TPF))
# A scene file, or a built-in scene's name (pbgi scenes).
if [ -e "$SCENE" ]; then SCENE=$(realpath "$SCENE"); fi
[ -f "$CAMERA_PATH" ] || die "camera path '$CAMERA_PATH' not found"
case "$PBGI" in
    */*) [ -x "$PBGI" ] || die "PBGI '$PBGI' is not executable"; PBGI=$(realpath "$PBGI") ;;
    *) command -v "$PBGI" >/dev/null || echo "shot.sh: warning: '$PBGI' not on PATH here" >&2 ;;
esac
command -v sbatch >/dev/null || die "sbatch not found (is Slurm installed? farm/slurm/one-node.sh)"

CAMERA_PATH=$(realpath "$CAMERA_PATH")
mkdir -p "$OUT"
OUT=$(realpath "$OUT")
mkdir -p "$OUT/tiles" "$OUT/frames" "$OUT/logs"
# Per-submission directory: generated batch scripts and success markers.
RUN=$(mktemp -d "$OUT/logs/run-$(date +%Y%m%d-%H%M%S)-XXXX")
mkdir -p "$RUN/status"

# Write a batch script: variable preamble (quoted with %q), then a fixed body.
gen() { # file body
    {
        echo '#!/usr/bin/env bash'
        echo 'set -u'
        printf 'PBGI=%q SCENE=%q CAMERA_PATH=%q OUT=%q STATUS=%q\n' \
            "$PBGI" "$SCENE" "$CAMERA_PATH" "$OUT" "$RUN/status"
        printf 'COLS=%q ROWS=%q TPF=%q\n' "$COLS" "$ROWS" "$TPF"
        # The arrays as bash declares them (printf '%q' of none prints '').
        declare -p EXTRA SETTINGS
        # finish NAME: run the command line in "$@", leave NAME.ok or NAME.fail
        cat <<'BODY'
finish() {
    local name=$1; shift
    echo "+ $*"
    "$@"; local rc=$?
    if [ "$rc" = 0 ]; then touch "$STATUS/$name.ok"; else echo "$rc" > "$STATUS/$name.fail"; fi
    echo "exit $rc"
    exit "$rc"
}
echo "job ${SLURM_JOB_ID:-?} task ${SLURM_ARRAY_TASK_ID:--} on $(hostname) at $(date +%T.%N)"
BODY
        printf '%s\n' "$2"
    } > "$1"
    chmod +x "$1"
}

gen "$RUN/bake.sh" 'finish bake "$PBGI" bake "$SCENE" -o "$OUT/scene.pbgi" "${SETTINGS[@]+"${SETTINGS[@]}"}"'
gen "$RUN/render.sh" 'k=$SLURM_ARRAY_TASK_ID
frame=$((k / TPF)) tile=$((k % TPF))
finish "render-$k" "$PBGI" render "$SCENE" --tree "$OUT/scene.pbgi" \
    --camera-path "$CAMERA_PATH" --frames "$frame" --tiles "$COLS,$ROWS" --tile "$tile" \
    -o "$OUT/tiles/frame-{}-tile-$tile.exr" "${SETTINGS[@]+"${SETTINGS[@]}"}" "${EXTRA[@]+"${EXTRA[@]}"}"'
gen "$RUN/stitch.sh" 'frame=$SLURM_ARRAY_TASK_ID
finish "stitch-$frame" "$PBGI" stitch "$OUT/tiles/frame-{}-tile-{tile}.exr" \
    --tiles "$COLS,$ROWS" --frames "$frame" -o "$OUT/frames/frame-{}.exr"'

SB=(sbatch --parsable --cpus-per-task="$CPUS_PER_TASK" ${SB_ARGS[@]+"${SB_ARGS[@]}"})
jid() { cut -d';' -f1; }           # --parsable prints "id" or "id;cluster"

BAKE=$("${SB[@]}" --job-name=pbgi-bake --output="$OUT/logs/bake-%j.out" "$RUN/bake.sh" | jid)
RENDER=$("${SB[@]}" --job-name=pbgi-render --array="0-$((NTASKS - 1))" \
    --dependency="afterok:$BAKE" --kill-on-invalid-dep=yes \
    --output="$OUT/logs/render-%A_%a.out" "$RUN/render.sh" | jid)
STITCH=$("${SB[@]}" --job-name=pbgi-stitch --array="0-$((FRAMES - 1))" \
    --dependency="afterok:$RENDER" --kill-on-invalid-dep=yes \
    --output="$OUT/logs/stitch-%A_%a.out" "$RUN/stitch.sh" | jid)

echo "bake=$BAKE"
echo "render=$RENDER ($NTASKS tasks: $FRAMES frames x $TPF tiles)"
echo "stitch=$STITCH ($FRAMES tasks)"
echo "logs: $OUT/logs  scripts/markers: $RUN"

[ "$WAIT" = 1 ] || exit 0

# Wait until none of the three jobs is in squeue any more (no sacct:
# accounting storage may be off), then count the markers the tasks left.
# %F is the array's job id (the job id itself for a non-array job).
errs=0
while :; do
    if q=$(squeue -h -o %F 2>&1); then
        errs=0
        grep -qxE "$BAKE|$RENDER|$STITCH" <<< "$q" || break
    else
        errs=$((errs + 1))
        [ "$errs" -ge 30 ] && { echo "shot.sh: squeue keeps failing: $q" >&2; break; }
    fi
    sleep 2
done

want=$((1 + NTASKS + FRAMES))
ok=$(find "$RUN/status" -name '*.ok' | wc -l)
if [ "$ok" -eq "$want" ]; then
    echo "done: all $want tasks succeeded; frames in $OUT/frames"
    exit 0
fi
echo "FAILED: $ok of $want tasks succeeded" >&2
for f in "$RUN"/status/*.fail; do
    [ -e "$f" ] && echo "  ${f##*/}: exit $(cat "$f")" >&2
done
[ -e "$RUN/status/bake.ok" ] || echo "  bake did not succeed: see $OUT/logs/bake-$BAKE.out" >&2
echo "  tasks with neither .ok nor .fail were cancelled (failed dependency) or never ran" >&2
exit 1
