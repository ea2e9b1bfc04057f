#!/bin/sh
# Reproduces docs/notebook/measurements.md's light-group table: renders scenes/groups.toml
# exactly at 1 and 4 spp, then in each cut mode with and without per-group
# error control, and compares every render with the exact one at the same
# spp (beauty and each group's layer). Takes about 15 minutes on one core.
# Usage: ci/measure-groups.sh OUT_DIR [path/to/lightcuts]
set -eu
out=${1:?usage: ci/measure-groups.sh OUT_DIR [lightcuts binary]}
bin=${2:-target/release/lightcuts}
scene=scenes/groups.toml
mkdir -p "$out"
for spp in 1 4; do
    [ -f "$out/exact$spp.exr" ] || "$bin" render "$scene" -o "$out/exact$spp.exr" --exact --spp "$spp" -q |
        grep -E "render time" | sed "s/^/exact $spp spp: /"
done
run() { # name spp arguments...
    name=$1 spp=$2
    shift 2
    "$bin" render "$scene" -o "$out/$name.exr" --spp "$spp" -q "$@" >"$out/$name.log"
    echo "== $name ($spp spp): $*"
    grep -E "render time|shadow rays |cut size" "$out/$name.log"
    "$bin" compare "$out/$name.exr" "$out/exact$spp.exr" | grep -E "^  mean |99th|light groups|^  [a-z]+ +[0-9]"
}
run bounded-none-1 1 --bounded --aovs albedo,N,Z,lightcuts
run bounded-pixel-1 1 --bounded --group-error pixel
run bounded-group-1 1 --bounded
run stochastic-pixel-1 1 --stochastic --group-error pixel
run stochastic-group-1 1 --stochastic
run bounded-pixel-4 4 --bounded --group-error pixel
run bounded-group-4 4 --bounded
run stochastic-pixel-4 4 --stochastic --group-error pixel
run stochastic-group-4 4 --stochastic
