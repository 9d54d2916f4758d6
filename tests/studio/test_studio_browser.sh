#!/usr/bin/env bash
# tests/studio/test_studio_browser.sh -- `panelize studio` in a real browser: starts the server on a
# free port with a generated bodice, and drives Debian's Chromium headless with playwright-core
# (studio_browser.mjs says what it checks). Screenshots and the downloaded DXF go to
# $PZ_BUILD_DIR/studio-screenshots (docs/studio.md describes them). Skips (77) when node, Chromium,
# playwright-core (npm ci at build time) or the built page is missing.
#
# SPDX-License-Identifier: GPL-3.0-or-later
set -u

source "$(dirname "$0")/../cli/lib.sh"
source "$(dirname "$0")/studio_lib.sh"

CHROMIUM=${PZ_CHROMIUM:-/usr/bin/chromium}
NPM_DIR=${PZ_STUDIO_NPM_DIR:-${PZ_BUILD_DIR:-}/studio-npm}
if ! command -v node >/dev/null; then
    echo "SKIPPED: node is missing (scripts/install-deps.sh installs nodejs)"
    exit 77
fi
if [ ! -x "$CHROMIUM" ]; then
    echo "SKIPPED: no Chromium at $CHROMIUM (scripts/install-deps.sh installs Debian's chromium)"
    exit 77
fi
if [ ! -f "$NPM_DIR/node_modules/playwright-core/package.json" ]; then
    echo "SKIPPED: no playwright-core in $NPM_DIR (the build runs npm ci when npm is there)"
    exit 77
fi
OUT=${PZ_BUILD_DIR:-$WORK}/studio-screenshots
rm -rf "$OUT"
mkdir -p "$OUT"

run generate bodice -o bodice.obj --faces 3000
expect_ok "generate bodice"
start_studio bodice.obj
api GET /
if [ "$code" != 200 ]; then
    echo "SKIPPED: the page was not built ($(head -c 200 "$WORK/body"))"
    exit 77
fi
export PZ_CHROMIUM=$CHROMIUM
# Ten minutes: the sanitizer build's runs are several times slower than the release build's.
timeout 600 node "$(dirname "$0")/studio_browser.mjs" "$URL" "$NPM_DIR" "$OUT"
node_rc=$?
check "the browser checks: exit $node_rc (screenshots in $OUT)" [ "$node_rc" -eq 0 ]
for shot in studio-loaded studio-stroke studio-strict; do
    check "screenshot $shot.png" [ -s "$OUT/$shot.png" ]
done
stop_studio
check "the server stops with exit 0 ($studio_rc)" [ "$studio_rc" = 0 ]
finish
