#!/bin/bash
# Reconstruction cuts (--reconstruct B, docs/design.md §9.6) beside the
# bounded and stochastic modes at the same samples per pixel, each against
# the exact render of the same samples, on windows of grid10k, the atrium
# and the depth-of-field scene. Prints a Markdown table: the render pass's
# wall time (tree build and scene load excluded), shadow rays per pixel
# (anchors included) and the errors.
# Usage: ci/reconstruction-table.sh [BINARY] [OUT_DIR]
# SPPS="4 16" and BLOCKS="2" narrow the sweep; SCENES as in the defaults.
set -euo pipefail
bin=${1:-target/release/lightcuts}
out=${2:-$(mktemp -d)}
mkdir -p "$out"
spps=${SPPS:-4 16 64}
blocks=${BLOCKS:-1 2 4}
default_scenes=("scenes/grid10k.toml 40,120,50,80 160x120" "scenes/atrium.toml 300,340,225,255 -" "scenes/dof.toml 64,96,44,68 160x120")
if [ -n "${SCENES:-}" ]; then entries=("$SCENES"); else entries=("${default_scenes[@]}"); fi
# Renders one entry; prints "EXR PASS_SECONDS RAYS_PER_PIXEL".
row() { # scene window resolution spp label mode-args...
    local scene=$1 window=$2 resolution=$3 spp=$4 label=$5
    shift 5
    local exr="$out/$(basename "$scene" .toml)-$spp-$label.exr"
    local size=()
    [ "$resolution" != "-" ] && size=(--resolution "$resolution")
    local stats
    stats=$("$bin" render "$scene" "$@" --spp "$spp" "${size[@]}" --pixel-bounds "$window" -o "$exr" --stats 2>/dev/null)
    local pass rays
    pass=$(echo "$stats" | awk '/render pass/ {print $3}')
    rays=$(echo "$stats" | sed -n 's/.*shadow rays .*(\(.*\) per pixel).*/\1/p')
    echo "$exr $pass $rays"
}
echo "| scene (window) | spp | mode | pass seconds | shadow rays per pixel | mean error | p99 error |"
echo "|---|---|---|---|---|---|---|"
for entry in "${entries[@]}"; do
    set -- $entry
    scene=$1 window=$2 resolution=$3
    name="$(basename "$scene") ($window)"
    for spp in $spps; do
        read -r reference seconds rays < <(row "$scene" "$window" "$resolution" "$spp" exact --exact)
        echo "| $name | $spp | exact | $seconds | $rays | 0 | 0 |"
        modes=("bounded --bounded" "stochastic --stochastic")
        for b in $blocks; do modes+=("reconstruct$b --reconstruct $b"); done
        for m in "${modes[@]}"; do
            set -- $m
            label=$1
            shift
            read -r exr seconds rays < <(row "$scene" "$window" "$resolution" "$spp" "$label" "$@")
            json=$("$bin" compare "$exr" "$reference" --json)
            errors=$(echo "$json" | python3 -c 'import json,sys; d=json.load(sys.stdin); print("%.2f%% | %.2f%%" % (100*d["mean_relative_error"], 100*d["p99_relative_error"]))')
            echo "| $name | $spp | ${label/reconstruct/reconstruct B=} | $seconds | $rays | $errors |"
        done
    done
done
