#!/usr/bin/env bash
# Installs what the browser tests need, idempotently (run by `make test` through the Makefile's `browser` target):
#   - Debian's `chromium` (apt),
#   - into .cache/browser/ (gitignored): the open-source Foxglove Studio web build
#     (`npm pack @foxglove/studio-base@1.48.0`, unpacked) and `puppeteer-core` (the driver; it downloads no browser).
# Any piece that cannot be installed makes this script exit 1 with a line saying which: `make test` then stops
# instead of letting the browser tests skip (under CI=true a skip of them is a failure anyway: tests/skip_guard.py).
set -uo pipefail
fail() { echo "setup: $*" >&2; exit 1; }

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
            || fail "could not install chromium (apt-get install chromium failed)"
    else
        fail "no apt-get; install chromium by hand"
    fi
fi
command -v chromium >/dev/null 2>&1 || fail "chromium is still missing after its install"
if ! command -v npm >/dev/null 2>&1 && command -v apt-get >/dev/null 2>&1; then
    DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends nodejs npm >/dev/null \
        || fail "could not install nodejs and npm (apt-get)"
fi
command -v npm >/dev/null 2>&1 || fail "npm is missing and could not be installed"

studio="$CACHE/studio-$STUDIO_VERSION"
if [ ! -f "$studio/package/assets/index.js" ]; then
    echo "setup: fetching @foxglove/studio-base@$STUDIO_VERSION (npm pack)"
    tmp="$(mktemp -d)"
    if (cd "$tmp" && npm pack --silent "@foxglove/studio-base@$STUDIO_VERSION" >/dev/null); then
        rm -rf "$studio" && mkdir -p "$studio"
        tar -xzf "$tmp"/*.tgz -C "$studio"
    else
        rm -rf "$tmp"
        fail "npm pack @foxglove/studio-base@$STUDIO_VERSION failed"
    fi
    rm -rf "$tmp"
fi
[ -f "$studio/package/assets/index.js" ] || fail "the Foxglove Studio bundle is missing in $studio"

if [ ! -f "$CACHE/node_modules/puppeteer-core/package.json" ] || [ ! -f "$CACHE/node_modules/react-dom/umd/react-dom.production.min.js" ] || [ ! -f "$CACHE/node_modules/ws/package.json" ]; then
    echo "setup: installing puppeteer-core, react and react-dom (npm)"
    (cd "$CACHE" && { [ -f package.json ] || echo '{"name":"bt-grasp-browser-tests","private":true}' > package.json; } \
        && PUPPETEER_SKIP_DOWNLOAD=1 npm install --silent --no-audit --no-fund "puppeteer-core@$PUPPETEER_VERSION" "ws@8" "react@$REACT_VERSION" "react-dom@$REACT_VERSION" >/dev/null) \
        || fail "npm install puppeteer-core, ws, react, react-dom failed"
fi
exit 0
