#!/usr/bin/env bash
# Makes Mesa 25's lavapipe (bookworm-backports `mesa-vulkan-drivers`) usable next to the
# system's Mesa 22, without installing it: the .deb is unpacked under target/mesa25 and an
# ICD manifest with an absolute library path is written there. Debian 12, run as root (it
# may add the backports apt source and install the driver's missing runtime libraries).
#
#   scripts/mesa25.sh && source target/mesa25/env.sh
#
# Prints the manifest's path and the env lines (also in target/mesa25/env.sh). The loader
# then sees only this driver (VK_ICD_FILENAMES replaces the system's ICD list).
set -euo pipefail
cd "$(dirname "$0")/.."
dest=$PWD/target/mesa25
icd=$dest/lvp_icd.json

done_msg() { echo "$icd"; cat "$dest/env.sh"; exit 0; }

# Already set up: nothing to do.
if [ -f "$icd" ] && [ -f "$dest/env.sh" ] &&
    lib=$(sed -n 's/.*"library_path": *"\([^"]*\)".*/\1/p' "$icd") && [ -f "$lib" ]; then
    done_msg
fi

as_root() { if [ "$(id -u)" = 0 ]; then "$@"; else sudo "$@"; fi; }
pkg=mesa-vulkan-drivers/bookworm-backports

# The backports suite isn't in Debian's default sources; add it (backports is pinned at
# priority 100, so this alone never upgrades anything) and refresh the lists only when apt
# doesn't know the backports package yet.
if ! grep -rqs '^[^#]*bookworm-backports' /etc/apt/sources.list /etc/apt/sources.list.d/; then
    echo 'deb http://deb.debian.org/debian bookworm-backports main' |
        as_root tee /etc/apt/sources.list.d/bookworm-backports.list >/dev/null
fi
# apt-cache show exits 0 even when it finds nothing, hence the grep (not -q: its early exit
# would SIGPIPE apt-cache and fail the pipe under pipefail).
known() { apt-cache show "$pkg" 2>/dev/null | grep '^Version:' >/dev/null; }
known || as_root apt-get update -q >&2
known || { echo "apt has no $pkg" >&2; exit 1; }

# Runtime libraries the driver links (libLLVM-15, xcb, wayland, ...): bookworm's own
# versions suffice, but a minimal system may lack some. Install only the missing ones
# (never Mesa itself); versions are stripped because e.g. libdrm2 (>= 2.4.121) is a
# packaging floor that bookworm's 2.4.114 meets in practice (checked with ldd -r below).
deps=$(apt-cache show "$pkg" | sed -n '0,/^Depends:/s/^Depends: //p' |
    tr ',' '\n' | sed 's/[|(].*//; s/ //g')
missing=$(for d in $deps; do
    [ "$(dpkg-query -W -f='${db:Status-Status}' "$d" 2>/dev/null)" = installed ] || echo "$d"
done)
if [ -n "$missing" ]; then
    as_root apt-get install -y -q --no-install-recommends $missing >&2
fi

# Download and unpack (no dpkg -i, so the system's Mesa stays). The temp dir must be
# writable by apt's _apt sandbox user, or apt warns and downloads unsandboxed.
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
chmod 777 "$tmp"
(cd "$tmp" && apt-get download -q "$pkg" >&2)
rm -rf "$dest" && mkdir -p "$dest"
root=$dest/root
dpkg -x "$tmp"/mesa-vulkan-drivers_*.deb "$root"
so=$(find "$root" -name libvulkan_lvp.so)

# lavapipe is one self-contained .so in Mesa 25 (no libgallium). If it still needs a newer
# library than the system has (missing symbols or versions), fall back to backports'
# libdrm2, the only dependency with a backports-only version floor, via LD_LIBRARY_PATH.
env_lines="export VK_ICD_FILENAMES=$icd"
if ldd -r "$so" 2>&1 | grep -E 'not found|undefined symbol' >&2; then
    echo "lavapipe needs newer libraries; adding backports' libdrm2" >&2
    (cd "$tmp" && apt-get download -q libdrm2/bookworm-backports >&2)
    dpkg -x "$tmp"/libdrm2_*.deb "$root"
    libdir=$(dirname "$so")
    if LD_LIBRARY_PATH=$libdir ldd -r "$so" 2>&1 | grep -E 'not found|undefined symbol' >&2; then
        echo "lavapipe still cannot load; see above" >&2
        exit 1
    fi
    env_lines+=$'\n'"export LD_LIBRARY_PATH=$libdir\${LD_LIBRARY_PATH:+:\$LD_LIBRARY_PATH}"
fi

# The package's manifest names the bare soname; point it at the unpacked copy.
sed "s|\"library_path\": *\"[^\"]*\"|\"library_path\": \"$so\"|" \
    "$root"/usr/share/vulkan/icd.d/lvp_icd*.json >"$icd"
echo "$env_lines" >"$dest/env.sh"
echo "lavapipe from $(dpkg-deb -f "$tmp"/mesa-vulkan-drivers_*.deb Version)" >&2
done_msg
