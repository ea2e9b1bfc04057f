#!/usr/bin/env bash
# Installs the Debian packages lightcuts needs. Idempotent: installs only what
# is missing, and does nothing (not even apt-get update) when all is present.
#
#   ci/setup.sh          to build and render: Embree (libembree-dev: Embree 3
#                        on Debian 12, Embree 4 on Debian 13), libclang for
#                        bindgen, a C compiler for the shim, and DejaVu Sans
#                        for the text of `sweep`'s plots
#   ci/setup.sh --test   also what the tests and CI use: git (tests/assets.rs
#                        checks that every file a scene reads is committed)
#                        and OpenImageIO's tools (an independent reader of the
#                        EXRs we write: oiiotool, iinfo, idiff)
#   ci/setup.sh --slurm  also Slurm and MUNGE, for ci/slurm-test.sh's
#                        single-node cluster (farm/slurm/)
set -euo pipefail

packages=(libembree-dev libclang-dev gcc libc6-dev fonts-dejavu-core)
case "${1:-}" in
"") ;;
--test) packages+=(git openimageio-tools) ;;
--slurm) packages+=(git openimageio-tools slurm-wlm munge) ;;
*)
    echo "usage: ci/setup.sh [--test | --slurm]" >&2
    exit 2
    ;;
esac

missing=()
for p in "${packages[@]}"; do
    if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
        missing+=("$p")
    fi
done

if [ ${#missing[@]} -eq 0 ]; then
    exit 0
fi

if [ "$(id -u)" -eq 0 ]; then
    sudo=()
elif command -v sudo >/dev/null 2>&1; then
    sudo=(sudo)
else
    echo "ci/setup.sh: need root (or sudo) to install: ${missing[*]}" >&2
    exit 1
fi

echo "ci/setup.sh: installing ${missing[*]}" >&2
"${sudo[@]}" env DEBIAN_FRONTEND=noninteractive apt-get update -qq
"${sudo[@]}" env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
