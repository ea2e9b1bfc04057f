#!/usr/bin/env bash
# Instructions per cut node outside Embree, counted by valgrind's callgrind
# (repeatable on a shared machine, unlike times): the render's calls into
# the bounded or stochastic cut, less the instructions inside Embree's
# library, over the cut nodes the render reports.
#
#   ci/profile-cut.sh [BIN] [SCENE] [WINDOW] [MODE] [RENDER FLAGS...]
#
# Defaults: target/release/lightcuts, scenes/grid10k.toml, its central 80x60
# window (280,360,200,260), --bounded; one thread. Flags after the fourth
# argument go to the render (e.g. --error 0.03). Needs valgrind.
set -euo pipefail
cd "$(dirname "$0")/.."
bin=${1:-target/release/lightcuts}
scene=${2:-scenes/grid10k.toml}
window=${3:-280,360,200,260}
mode=${4:---bounded}
shift $(($# < 4 ? $# : 4))
command -v valgrind >/dev/null || { echo "ci/profile-cut.sh: needs valgrind (apt-get install valgrind)" >&2; exit 1; }
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
# The cut's entry points: every instruction from there down is counted.
case "$mode" in
--bounded) entry="*::lightcut::cut::evaluate" ;;
--stochastic) entry="*::lightcut::stochastic::evaluate" ;;
*) echo "ci/profile-cut.sh: MODE is --bounded or --stochastic" >&2; exit 2 ;;
esac
valgrind --tool=callgrind --callgrind-out-file="$out/cg" "--toggle-collect=$entry" \
    "$bin" render "$scene" -o "$out/o.exr" --pixel-bounds "$window" --threads 1 --quiet --stats "$mode" "$@" >"$out/stats" 2>"$out/valgrind"
nodes=$(awk '/cut work/ { for (i = 1; i <= NF; i++) if ($i == "nodes") print $(i - 1) }' "$out/stats")
callgrind_annotate "$out/cg" >"$out/annotated" 2>/dev/null
total=$(awk '/PROGRAM TOTALS/ { gsub(",", "", $1); print $1 }' "$out/annotated")
embree=$(awk '/libembree/ { gsub(",", "", $1); s += $1 } END { print s + 0 }' "$out/annotated")
awk -v t="$total" -v e="$embree" -v n="$nodes" 'BEGIN {
    printf "cut nodes %d, instructions in the cut %.0f, of which in Embree %.0f: %.0f instructions per cut node outside Embree\n", n, t, e, (t - e) / n
}'
