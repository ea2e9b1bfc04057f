#!/bin/bash
# The multidimensional mode against the bounded, reconstruction (B = 2) and
# stochastic modes (and the stochastic mode with one, three or four lights
# drawn over a fine cut, `cut-draws`, `cut-draws-3` and `cut-draws-4`) at the
# same samples per pixel (16, 64, 256 gather points per pixel from camera
# samples), each against the exact render of the same gather points, on
# windows of the depth-of-field scene, the Cornell box and the motion-blur
# scene (where the exact render of the whole frame would take hours).
# Prints a Markdown table.
# Usage: ci/multidimensional-table.sh [BINARY] [OUT_DIR]
# SCENES="scenes/motion.toml 24,56,50,74" measures the listed entries only.
set -euo pipefail
bin=${1:-target/release/lightcuts}
out=${2:-$(mktemp -d)}
mkdir -p "$out"
row() { # scene window spp mode-args label
    local scene=$1 window=$2 spp=$3 label=$5
    local exr="$out/$(basename "$scene" .toml)-$spp-$label.exr"
    local start end
    start=$(date +%s.%N)
    "$bin" render "$scene" $4 --spp "$spp" --resolution 160x120 --pixel-bounds "$window" -o "$exr" --quiet > /dev/null
    end=$(date +%s.%N)
    echo "$exr $(echo "$end - $start" | bc)"
}
ratio() { # seconds reference-seconds
    echo "scale=1; $1 / $2" | bc
}
echo "| scene (window) | spp | mode | seconds | x bounded 1 spp | mean error | p99 error |"
echo "|---|---|---|---|---|---|---|"
default_scenes=("scenes/dof.toml 64,96,44,68" "scenes/cornell.toml 60,92,60,84" "scenes/motion.toml 24,56,50,74")
if [ -n "${SCENES:-}" ]; then entries=("$SCENES"); else entries=("${default_scenes[@]}"); fi
for entry in "${entries[@]}"; do
    set -- $entry
    scene=$1 window=$2
    read -r _ one < <(row "$scene" "$window" 1 "--bounded" bounded1)
    echo "| $(basename "$scene") ($window) | 1 | bounded | $one | 1 | | |"
    for spp in 16 64 256; do
        read -r reference exact_seconds < <(row "$scene" "$window" "$spp" "--exact" exact)
        echo "| $(basename "$scene") ($window) | $spp | exact | $exact_seconds | $(ratio "$exact_seconds" "$one") | 0 | 0 |"
        for mode in multidimensional bounded reconstruct stochastic cut-draws cut-draws-3 cut-draws-4; do
            # Reconstruction cuts over 2 x 2 blocks (docs/design.md §9.6);
            # one, three or four lights drawn a point over a fine cut (§10.10).
            case "$mode" in
                reconstruct) args="--reconstruct 2" ;;
                cut-draws) args="--stochastic --error 0.02 --cut-draws 1" ;;
                cut-draws-*) args="--stochastic --error 0.02 --cut-draws ${mode#cut-draws-}" ;;
                *) args="--$mode" ;;
            esac
            read -r exr seconds < <(row "$scene" "$window" "$spp" "$args" "$mode")
            json=$("$bin" compare "$exr" "$reference" --json)
            mean=$(echo "$json" | python3 -c 'import json,sys; print("%.2f%%" % (100*json.load(sys.stdin)["mean_relative_error"]))')
            p99=$(echo "$json" | python3 -c 'import json,sys; print("%.2f%%" % (100*json.load(sys.stdin)["p99_relative_error"]))')
            echo "| $(basename "$scene") ($window) | $spp | $mode | $seconds | $(ratio "$seconds" "$one") | $mean | $p99 |"
        done
    done
done
