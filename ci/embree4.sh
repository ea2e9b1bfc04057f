#!/usr/bin/env bash
# Builds lightcuts and runs its full test suite against Embree 4 from Debian 13
# (trixie), inside a debootstrapped trixie root. Needs root (debootstrap and
# chroot).
#
# Independent of what ran before it on the machine:
# - the Debian mirror is the host's own (read from its apt sources), so it
#   works wherever the host's apt works; LIGHTCUTS_DEBIAN_MIRROR overrides it;
# - the crates are fetched on the host (`cargo fetch --locked`, with the
#   host's CA certificates), and the root builds offline from that CARGO_HOME,
#   so the root needs neither network access to the registry nor certificates;
# - the host's Rust toolchain is bind-mounted (its sysroot, not rustup's proxies,
#   so an empty CARGO_HOME works too).
# The root and the build directory are cached under $LIGHTCUTS_TRIXIE_CACHE
# (default /var/cache/lightcuts); the root is rebuilt when its package list
# changes.
set -euo pipefail

repo=$(cd "$(dirname "$0")/.." && pwd)
cache=${LIGHTCUTS_TRIXIE_CACHE:-/var/cache/lightcuts}
root="$cache/trixie-root"
cargo_home=${CARGO_HOME:-$HOME/.cargo}
# git: tests/assets.rs asks git which files are committed; fonts-dejavu-core:
# the plots' text; openimageio-tools: tests/oiio.rs reads every kind of file
# the renderer writes with a reader that is not ours (nothing is skipped).
packages=libembree-dev,libclang-dev,gcc,libc6-dev,ca-certificates,git,fonts-dejavu-core,openimageio-tools

if [ "$(id -u)" -ne 0 ]; then
    echo "ci/embree4.sh: must run as root (debootstrap and chroot)" >&2
    exit 1
fi

# The first Debian archive the host's apt uses for its own release (the
# entry whose suite is the host's codename), from the one-line sources.list
# format and the deb822 .sources format.
host_mirror() {
    local codename
    codename=$(. /etc/os-release && echo "${VERSION_CODENAME:-}")
    [ -n "$codename" ] || return 1
    {
        for f in /etc/apt/sources.list /etc/apt/sources.list.d/*.list; do
            [ -f "$f" ] || continue
            # deb [options] URI suite components...
            awk -v c="$codename" '$1 == "deb" {
                i = 2
                if ($i ~ /^\[/) { while (i <= NF && $i !~ /\]$/) i++; i++ }
                if ($(i + 1) == c) print $i
            }' "$f"
        done
        for f in /etc/apt/sources.list.d/*.sources; do
            [ -f "$f" ] || continue
            awk -v c="$codename" 'BEGIN { RS = ""; FS = "\n" } {
                types = ""; uris = ""; suites = ""; enabled = "yes"
                for (k = 1; k <= NF; k++) {
                    line = $k
                    if (line ~ /^Types:/) { sub(/^Types:[ \t]*/, "", line); types = line }
                    if (line ~ /^URIs:/) { sub(/^URIs:[ \t]*/, "", line); uris = line }
                    if (line ~ /^Suites:/) { sub(/^Suites:[ \t]*/, "", line); suites = line }
                    if (line ~ /^Enabled:/) { sub(/^Enabled:[ \t]*/, "", line); enabled = line }
                }
                if (enabled == "no" || (" " types " ") !~ / deb /) next
                n = split(suites, s, /[ \t]+/)
                for (j = 1; j <= n; j++) if (s[j] == c) { split(uris, u, /[ \t]+/); print u[1]; next }
            }' "$f"
        done
    } | head -n 1 | grep .
}

if [ -n "${LIGHTCUTS_DEBIAN_MIRROR:-}" ]; then
    mirror=$LIGHTCUTS_DEBIAN_MIRROR
elif ! mirror=$(host_mirror); then
    echo "ci/embree4.sh: found no Debian archive for this host's release in /etc/apt/sources.list or" \
        "/etc/apt/sources.list.d/; set LIGHTCUTS_DEBIAN_MIRROR to a Debian mirror that serves trixie" >&2
    exit 1
fi

ready="$root/.lightcuts-ready"
if [ ! -f "$ready" ] || [ "$(cat "$ready")" != "$packages" ]; then
    if ! command -v debootstrap >/dev/null 2>&1; then
        DEBIAN_FRONTEND=noninteractive apt-get update -qq
        DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends debootstrap >/dev/null
    fi
    echo "ci/embree4.sh: bootstrapping Debian 13 from $mirror into $root" >&2
    rm -rf "$root"
    mkdir -p "$cache"
    debootstrap --variant=minbase --include="$packages" trixie "$root" "$mirror" >"$cache/debootstrap.log" 2>&1 || {
        tail -20 "$cache/debootstrap.log" >&2
        exit 1
    }
    echo "$packages" >"$ready"
fi

if [ ! -f "$root/usr/include/embree4/rtcore_config.h" ]; then
    echo "ci/embree4.sh: the trixie root has no Embree 4 headers" >&2
    exit 1
fi

# Every crate Cargo.lock names, fetched by the host's cargo into $cargo_home.
mkdir -p "$cargo_home"
echo "ci/embree4.sh: fetching the locked crates into $cargo_home" >&2
(cd "$repo" && CARGO_HOME="$cargo_home" cargo fetch --locked --quiet)
sysroot=$(rustc --print sysroot)

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
bind "$sysroot" /opt/rust

echo "ci/embree4.sh: building and testing against $(grep -h 'define RTC_VERSION_STRING' "$root/usr/include/embree4/rtcore_config.h")" >&2
chroot "$root" /usr/bin/env -i \
    HOME=/root PATH=/opt/rust/bin:/usr/bin:/bin \
    CARGO_HOME=/opt/cargo \
    CARGO_TARGET_DIR=/var/cache/lightcuts-target \
    LIGHTCUTS_EXPECT_EMBREE_MAJOR=4 \
    bash -c 'cd /src && cargo test --release --locked --offline'
