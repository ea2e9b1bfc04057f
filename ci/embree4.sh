#!/usr/bin/env bash
# Builds lightcuts and runs its full test suite against Embree 4 from Debian 13
# (trixie), inside a debootstrapped trixie root. The root and the build
# directory are cached under $LIGHTCUTS_TRIXIE_CACHE (default
# /var/cache/lightcuts) between runs on the same machine. The host's Rust
# toolchain and cargo registry are bind-mounted into the root. Needs root.
set -euo pipefail

repo=$(cd "$(dirname "$0")/.." && pwd)
cache=${LIGHTCUTS_TRIXIE_CACHE:-/var/cache/lightcuts}
root="$cache/trixie-root"
mirror=${LIGHTCUTS_DEBIAN_MIRROR:-http://deb.debian.org/debian}
cargo_home=${CARGO_HOME:-$HOME/.cargo}
rustup_home=${RUSTUP_HOME:-$HOME/.rustup}
packages=libembree-dev,libclang-dev,gcc,libc6-dev,ca-certificates

if [ "$(id -u)" -ne 0 ]; then
    echo "ci/embree4.sh: must run as root (debootstrap and chroot)" >&2
    exit 1
fi

if [ ! -f "$root/.lightcuts-ready" ]; then
    if ! command -v debootstrap >/dev/null 2>&1; then
        DEBIAN_FRONTEND=noninteractive apt-get update -qq
        DEBIAN_FRONTEND=noninteractive apt-get install -y -qq debootstrap >/dev/null
    fi
    echo "ci/embree4.sh: bootstrapping Debian 13 into $root" >&2
    rm -rf "$root"
    mkdir -p "$cache"
    debootstrap --variant=minbase --include="$packages" trixie "$root" "$mirror" >"$cache/debootstrap.log" 2>&1 || {
        tail -20 "$cache/debootstrap.log" >&2
        exit 1
    }
    touch "$root/.lightcuts-ready"
fi

if [ ! -f "$root/usr/include/embree4/rtcore_config.h" ]; then
    echo "ci/embree4.sh: the trixie root has no Embree 4 headers" >&2
    exit 1
fi

mounts=()
cleanup() {
    for ((i = ${#mounts[@]} - 1; i >= 0; i--)); do
        umount -l "${mounts[$i]}" 2>/dev/null || true
    done
}
trap cleanup EXIT

bind() { # bind SOURCE TARGET-INSIDE-ROOT
    mkdir -p "$root$2"
    mount --bind "$1" "$root$2"
    mounts+=("$root$2")
}
mount -t proc proc "$root/proc" && mounts+=("$root/proc")
bind /dev /dev
bind "$repo" /src
bind "$cargo_home" /opt/cargo
bind "$rustup_home" /opt/rustup
cp -L /etc/resolv.conf "$root/etc/resolv.conf" 2>/dev/null || true

echo "ci/embree4.sh: building and testing against $(grep -h 'define RTC_VERSION_STRING' "$root/usr/include/embree4/rtcore_config.h")" >&2
chroot "$root" /usr/bin/env -i \
    HOME=/root PATH=/opt/cargo/bin:/usr/bin:/bin \
    CARGO_HOME=/opt/cargo RUSTUP_HOME=/opt/rustup \
    CARGO_TARGET_DIR=/var/cache/lightcuts-target \
    LIGHTCUTS_EXPECT_EMBREE_MAJOR=4 \
    bash -c 'cd /src && cargo test --release --locked'
