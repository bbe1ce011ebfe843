#!/usr/bin/env bash
# Installs the system pieces bt_grasp needs, idempotently:
#   - libusb-1.0 (open3d's import needs it), graphviz, chromium and tmux (tests with real clients),
#   - a Vulkan loader and, where no GPU Vulkan driver exists, Mesa's software driver lavapipe >= 24.3
#     (SAPIEN needs VK_KHR_external_semaphore_fd, which lavapipe gained in Mesa 24.3; on Debian 12 that
#     means the bookworm-backports suite).
# A machine with an NVIDIA driver keeps its own Vulkan driver: nothing is forced.
set -euo pipefail

SUDO=""
if [ "$(id -u)" != "0" ]; then
    if command -v sudo >/dev/null 2>&1; then SUDO="sudo"; else
        echo "setup: not root and no sudo; install libusb-1.0-0 libvulkan1 and mesa-vulkan-drivers (>= 24.3) by hand" >&2
        exit 1
    fi
fi

have_pkg() { dpkg-query -W -f='${Status}' "$1" 2>/dev/null | grep -q "install ok installed"; }
pkg_version() { dpkg-query -W -f='${Version}' "$1" 2>/dev/null || true; }
APT_UPDATED=0
apt_update() { if [ "$APT_UPDATED" = 0 ]; then $SUDO apt-get update -qq; APT_UPDATED=1; fi; }
apt_install() { DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "$@" >/dev/null; }

need=()
# chromium: the campaign report and browser tests are checked in a real headless browser
# tmux: `bt-grasp run --interactive` is tested in a real terminal (tests/control/test_terminal_tmux.py)
for p in libusb-1.0-0 libvulkan1 libgomp1 graphviz chromium tmux; do have_pkg "$p" || need+=("$p"); done
if [ "${#need[@]}" -gt 0 ]; then
    echo "setup: installing ${need[*]}"
    apt_update
    apt_install "${need[@]}"
fi

if command -v nvidia-smi >/dev/null 2>&1 && nvidia-smi -L >/dev/null 2>&1; then
    echo "setup: NVIDIA GPU found; using its Vulkan driver"
    exit 0
fi

mesa_ok() {
    local v; v="$(pkg_version mesa-vulkan-drivers)"
    [ -n "$v" ] && dpkg --compare-versions "$v" ge 24.3
}
if mesa_ok; then exit 0; fi

. /etc/os-release
if [ "${ID:-}" = "debian" ] && [ "${VERSION_CODENAME:-}" = "bookworm" ]; then
    src=/etc/apt/sources.list.d/bookworm-backports.list
    if ! grep -rqs "bookworm-backports" /etc/apt/sources.list /etc/apt/sources.list.d/; then
        echo "setup: adding the bookworm-backports suite for Mesa >= 24.3 (lavapipe)"
        echo "deb http://deb.debian.org/debian bookworm-backports main" | $SUDO tee "$src" >/dev/null
        APT_UPDATED=0
    fi
    apt_update
    echo "setup: installing mesa-vulkan-drivers from bookworm-backports"
    apt_install -t bookworm-backports mesa-vulkan-drivers
else
    apt_update
    echo "setup: installing mesa-vulkan-drivers"
    apt_install mesa-vulkan-drivers
fi
if ! mesa_ok; then
    echo "setup: mesa-vulkan-drivers $(pkg_version mesa-vulkan-drivers) is older than 24.3; SAPIEN will not accept lavapipe" >&2
    exit 1
fi
