#!/usr/bin/env bash
# Renders SCENE in TILES tiles on Slurm and assembles them:
#
#   farm/slurm/submit.sh SCENE OUT_DIR TILES [lightcuts render options...]
#
# Submits an array job (one task per tile, farm/slurm/render-tile.sbatch)
# and an assemble job that runs when every task succeeded
# (--dependency=afterok; cancelled by Slurm if a task fails). Prints the two
# job ids. OUT_DIR, the scene and LIGHTCUTS (the binary, default: lightcuts
# on the PATH) must be on a filesystem every node sees. Re-running the same
# command renders only the tiles that are missing. Logs: OUT_DIR/logs/.
set -euo pipefail
if [ $# -lt 3 ]; then
    echo "usage: farm/slurm/submit.sh SCENE OUT_DIR TILES [render options...]" >&2
    exit 2
fi
here=$(cd "$(dirname "$0")" && pwd)
scene=$(realpath "$1")
mkdir -p "$2/logs"
out=$(realpath "$2")
tiles=$3
shift 3
lightcuts=$(realpath "${LIGHTCUTS:-$(command -v lightcuts)}")
export LIGHTCUTS="$lightcuts" SCENE="$scene" OUT_DIR="$out" TILES="$tiles" RENDER_ARGS="$*"
array=$(sbatch --parsable --array="0-$((tiles - 1))" --export=ALL \
    --output="$out/logs/tile-%a.log" ${SBATCH_ARGS:-} "$here/render-tile.sbatch")
array=${array%%;*}
assemble=$(sbatch --parsable --dependency="afterok:$array" --kill-on-invalid-dep=yes --export=ALL \
    --output="$out/logs/assemble.log" ${SBATCH_ARGS:-} "$here/assemble.sbatch")
echo "$array ${assemble%%;*}"
