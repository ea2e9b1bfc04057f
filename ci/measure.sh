#!/usr/bin/env bash
# Measures lightcuts at 2% against the exact render on the measuring scenes:
# time of each, speedup (ratio from one run each), average cut size, and the
# error of the lightcuts image against the exact one (lightcuts compare).
# Usage: ci/measure.sh [OUTDIR]   (not part of CI: the exact renders take minutes)
# Big scenes are measured on a window (see WINDOWS) because their exact render
# at full resolution takes hours here.
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:-out/measure}
mkdir -p "$out"
# BIN=path/to/lightcuts measures another build (e.g. the previous one) the same way.
if [ -z "${BIN:-}" ]; then
    cargo build --release --quiet
fi
bin=${BIN:-target/release/lightcuts}

declare -A WINDOWS=(
    [grid100k]="280,360,210,270"
    [cornell]="224,288,224,288"
    [atrium]="300,340,225,255"
)

printf '| scene | lights (omni / oriented / directional) | triangles | window | exact (s) | lightcuts 2%% (s) | speedup | avg cut | mean rel. err | p99 rel. err | px > 2%% |\n'
printf '|---|---|---|---|---|---|---|---|---|---|---|\n'
for scene in ${SCENES:-few4 grid100 grid10k grid100k}; do
    window=()
    label="full"
    if [ -n "${WINDOWS[$scene]:-}" ]; then
        window=(--pixel-bounds "${WINDOWS[$scene]}")
        label="${WINDOWS[$scene]}"
    fi
    exact_log=$("$bin" render "scenes/$scene.toml" -o "$out/$scene-exact.exr" --exact --quiet "${window[@]}")
    lc_log=$("$bin" render "scenes/$scene.toml" -o "$out/$scene-lc.exr" --quiet "${window[@]}" --png "$out/$scene-lc.png")
    "$bin" compare "$out/$scene-lc.exr" "$out/$scene-exact.exr" --json --diff "$out/$scene-diff.png" >"$out/$scene-compare.json"
    t_exact=$(echo "$exact_log" | awk '/render time/ {print $3}')
    t_lc=$(echo "$lc_log" | awk '/render time/ {print $3}')
    lights=$(echo "$lc_log" | awk '/^  lights/ {gsub(/[(),]/, ""); print $2 " (" $4 " / " $6 " / " $8 ")"}')
    triangles=$(echo "$lc_log" | awk '/^  triangles/ {print $2}')
    cut=$(echo "$lc_log" | awk '/cut size/ {gsub(",", "", $4); print $4}')
    python3 - "$scene" "$lights" "$triangles" "$label" "$t_exact" "$t_lc" "$cut" "$out/$scene-compare.json" <<'PY'
import json, sys
scene, lights, triangles, label, te, tl, cut, path = sys.argv[1:]
c = json.load(open(path))
print(f"| {scene} | {lights} | {triangles} | {label} | {float(te):.2f} | {float(tl):.2f} | {float(te)/float(tl):.1f}x | {cut} | "
      f"{100*c['mean_relative_error']:.3f}% | {100*c['p99_relative_error']:.2f}% | {100*c['fraction_above_2_percent']:.2f}% |")
PY
done
