#!/usr/bin/env bash
# What the cut may cost, per node, for each speed target of the cut's issue
# to hold: the target's time budget, less what the cut does not control
# (Embree's queries on the cut's own shadow rays, the tree build, the rest
# of the render), over the cut's nodes. Printed beside the cost measured.
# One thread throughout, so that thread-seconds are seconds.
#
#   ci/ceiling.sh [BIN]     (not part of CI: the exact renders take minutes)
#
# Targets: grid10k's full frame 50x faster than exact; grid100k's central
# window 200x; atrium's full frame 1.5x faster than BIN's own render; on
# grid10k's window (`bench rays`), the lightcut pass at 0.7 of Embree's rate
# on batches of single rays and 0.5 of its rate on packets of 8 (both on
# the exact renderer's rays), and 0.7 of Embree's rate on the pass's own.
set -euo pipefail
cd "$(dirname "$0")/.."
bin=${1:-target/release/lightcuts}
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT

# stats FILE: "render_s embree_s cut_s nodes rays pass_s" from a render's
# --stats.
stats() {
    awk '/render time/ { r = $3 }
         /render pass/ { p = $3 }
         /Embree .* in ray queries/ { e = $2 }
         /cut work/ { gsub(/[(]/, ""); c = $8; for (i = 1; i <= NF; i++) if ($i == "nodes") n = $(i - 1) }
         /^  shadow rays / { s = $3 }
         END { print r, e, c, n, s, p }' "$1"
}

# row LABEL BUDGET_S RENDER_S EMBREE_S CUT_S NODES: the budget less what is
# not the cut, per node, and the cut's cost now.
row() {
    awk -v l="$1" -v b="$2" -v r="$3" -v e="$4" -v c="$5" -v n="$6" 'BEGIN {
        other = r - e - c
        allowed = (b - e - other) / n * 1e9
        printf "| %s | %.3f | %.3f | %.3f | %.3f | %s | %.0f | %.1f |\n", l, b, e, other, c, n, allowed, c / n * 1e9
    }'
}

render() { "$bin" render "$@" --threads 1 --stats --quiet -o "$out/o.exr"; }

printf '| target | budget (s) | Embree on the cut'"'"'s rays (s) | tree build and the rest (s) | cut now (s) | cut nodes | ns per node allowed | ns per node now |\n'
printf '|---|---|---|---|---|---|---|---|\n'

render scenes/grid10k.toml --exact >"$out/exact"
render scenes/grid10k.toml >"$out/lc"
read -r exact _ <<<"$(stats "$out/exact")"
read -r r e c n _ <<<"$(stats "$out/lc")"
row "grid10k, 50x exact ($exact s)" "$(awk -v x="$exact" 'BEGIN { print x / 50 }')" "$r" "$e" "$c" "$n"

w=280,360,210,270
render scenes/grid100k.toml --pixel-bounds $w --exact >"$out/exact"
render scenes/grid100k.toml --pixel-bounds $w >"$out/lc"
read -r exact _ <<<"$(stats "$out/exact")"
read -r r e c n _ <<<"$(stats "$out/lc")"
row "grid100k $w, 200x exact ($exact s)" "$(awk -v x="$exact" 'BEGIN { print x / 200 }')" "$r" "$e" "$c" "$n"

render scenes/atrium.toml >"$out/lc"
read -r r e c n _ <<<"$(stats "$out/lc")"
row "atrium, 1.5x faster than now ($r s)" "$(awk -v x="$r" 'BEGIN { print x / 1.5 }')" "$r" "$e" "$c" "$n"

# bench rays: the pass's time for the cut's rays at 0.7 (0.5) of Embree's
# rate on its recorded rays; what is not the cut from a render of the window.
w=280,360,200,260
"$bin" bench rays scenes/grid10k.toml --pixel-bounds $w --threads 1 --json >"$out/rays.json"
render scenes/grid10k.toml --pixel-bounds $w >"$out/lc"
# The bench times the pass alone: compare it with the render's pass.
read -r _ e c n s r <<<"$(stats "$out/lc")"
field() { awk -v k="\"$1\"" -F': *' '$1 ~ k { gsub(/,/, "", $2); print $2 }' "$out/rays.json"; }
batch=$(field embree_batch_mrays_per_s)
packets=$(field embree_packet8_mrays_per_s)
row "bench rays, 0.7 of Embree's batches ($batch Mrays/s)" "$(awk -v s="$s" -v x="$batch" 'BEGIN { print s / (0.7 * x * 1e6) }')" "$r" "$e" "$c" "$n"
row "bench rays, 0.5 of Embree's packets of 8 ($packets Mrays/s)" "$(awk -v s="$s" -v x="$packets" 'BEGIN { print s / (0.5 * x * 1e6) }')" "$r" "$e" "$c" "$n"
# The same ratio on the pass's own rays (`lightcuts_over_embree_own_rays`):
# the pass may take the render's Embree time over 0.7.
row "bench rays, 0.7 of Embree on the pass's own rays" "$(awk -v x="$e" 'BEGIN { print x / 0.7 }')" "$r" "$e" "$c" "$n"
