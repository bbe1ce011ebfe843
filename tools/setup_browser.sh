#!/usr/bin/env bash
# Installs what the browser tests need, idempotently (run by `make test` through the Makefile's `browser` target):
#   - Debian's `chromium` (apt),
#   - into .cache/browser/ (gitignored): the open-source Foxglove Studio web build
#     (`npm pack @foxglove/studio-base@1.48.0`, unpacked) and `puppeteer-core` (the driver; it downloads no browser).
# A machine without apt or npm is told what is missing and the browser tests skip with that reason.
set -uo pipefail

ROOT="$(cd "$(dirname "$0")/.." && pwd)"
CACHE="${BT_GRASP_BROWSER_CACHE:-$ROOT/.cache/browser}"
STUDIO_VERSION="1.48.0"
PUPPETEER_VERSION="24"
REACT_VERSION="17.0.2"  # the React the studio-base 1.48 bundle was built against (it expects it as a global)
mkdir -p "$CACHE"

SUDO=""
if [ "$(id -u)" != "0" ] && command -v sudo >/dev/null 2>&1; then SUDO="sudo"; fi

if ! command -v chromium >/dev/null 2>&1; then
    if command -v apt-get >/dev/null 2>&1; then
        echo "setup: installing chromium (apt)"
        $SUDO apt-get update -qq || true
        DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends chromium >/dev/null \
            || echo "setup: could not install chromium; browser tests will skip" >&2
    else
        echo "setup: no apt-get; install chromium by hand or browser tests will skip" >&2
    fi
fi
if ! command -v npm >/dev/null 2>&1 && command -v apt-get >/dev/null 2>&1; then
    DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends nodejs npm >/dev/null \
        || echo "setup: could not install npm; browser tests will skip" >&2
fi
if ! command -v npm >/dev/null 2>&1; then
    echo "setup: npm missing; browser tests will skip" >&2
    exit 0
fi

studio="$CACHE/studio-$STUDIO_VERSION"
if [ ! -f "$studio/package/assets/index.js" ]; then
    echo "setup: fetching @foxglove/studio-base@$STUDIO_VERSION (npm pack)"
    tmp="$(mktemp -d)"
    if (cd "$tmp" && npm pack --silent "@foxglove/studio-base@$STUDIO_VERSION" >/dev/null); then
        rm -rf "$studio" && mkdir -p "$studio"
        tar -xzf "$tmp"/*.tgz -C "$studio"
    else
        echo "setup: npm pack @foxglove/studio-base failed; browser tests will skip" >&2
    fi
    rm -rf "$tmp"
fi

if [ ! -f "$CACHE/node_modules/puppeteer-core/package.json" ] || [ ! -f "$CACHE/node_modules/react-dom/umd/react-dom.production.min.js" ] || [ ! -f "$CACHE/node_modules/ws/package.json" ]; then
    echo "setup: installing puppeteer-core, react and react-dom (npm)"
    (cd "$CACHE" && { [ -f package.json ] || echo '{"name":"bt-grasp-browser-tests","private":true}' > package.json; } \
        && PUPPETEER_SKIP_DOWNLOAD=1 npm install --silent --no-audit --no-fund "puppeteer-core@$PUPPETEER_VERSION" "ws@8" "react@$REACT_VERSION" "react-dom@$REACT_VERSION" >/dev/null) \
        || echo "setup: npm install puppeteer-core failed; browser tests will skip" >&2
fi
exit 0
