#!/usr/bin/env bash
# Renders the measuring scenes (ci/measure.sh's set, plus cornell, atrium,
# the light groups' scene and the glTF lobby) by every method with one binary,
# or checks that two such sets are bit-identical.
#
#   ci/same-images.sh render BIN OUTDIR    renders every scene by every method
#                                          (exact, bounded, bounded with
#                                          reconstruction cuts, stochastic,
#                                          stochastic with reuse,
#                                          multidimensional)
#   ci/same-images.sh compare DIR_A DIR_B  exits non-zero unless every channel
#                                          of every pair is identical (idiff -fail 0)
#
# Used to show that a refactoring changes no image: render with the old
# binary, render with the new, compare. Big scenes use windows so that the
# whole set renders in about two minutes.
set -euo pipefail
cd "$(dirname "$0")/.."

declare -A WINDOWS=(
    [grid10k]="240,400,180,300"
    [grid100k]="280,360,210,270"
    [cornell]="224,288,224,288"
    [atrium]="300,340,225,255"
    [groups]="180,300,100,180"
    [lobby]="40,120,30,90"
)
SCENES=${SCENES:-few4 grid100 grid10k grid100k cornell atrium groups lobby}
MODES=${MODES:-exact bounded reconstruct stochastic reuse multidimensional}

# The command-line flags of each mode.
flags() {
    case $1 in
    reconstruct) echo "--method bounded --reconstruct 4" ;;
    reuse) echo "--method stochastic --reuse 2" ;;
    *) echo "--method $1" ;;
    esac
}

case "${1:-}" in
render)
    bin=$2 out=$3
    mkdir -p "$out"
    for scene in $SCENES; do
        window=()
        if [ -n "${WINDOWS[$scene]:-}" ]; then window=(--pixel-bounds "${WINDOWS[$scene]}"); fi
        for mode in $MODES; do
            "$bin" render "scenes/$scene.toml" -o "$out/$scene-$mode.exr" $(flags "$mode") --quiet "${window[@]}" >/dev/null
        done
        echo "rendered $scene" >&2
    done
    ;;
compare)
    a=$2 b=$3 status=0
    command -v idiff >/dev/null || { echo "ci/same-images.sh: needs idiff (ci/setup.sh --test)" >&2; exit 1; }
    for scene in $SCENES; do
        for mode in $MODES; do
            if idiff -q -fail 0 -failpercent 0 -warn 0 "$a/$scene-$mode.exr" "$b/$scene-$mode.exr" >/dev/null; then
                echo "identical  $scene $mode"
            else
                echo "DIFFERENT  $scene $mode"
                status=1
            fi
        done
    done
    exit $status
    ;;
*)
    sed -n '2,10p' "$0" >&2
    exit 2
    ;;
esac
