#!/usr/bin/env bash
# CI: the browser preview (web/) and the three.js module (web/irid-three.mjs)
# in headless Chromium. Installs what is missing (Debian's chromium, node and
# npm; playwright-core and three from tools/web/package-lock.json), builds
# irid, exports five stacks, writes a preview of them with `irid preview`,
# and runs tools/web/test_web.mjs and tools/web/test_three.mjs.
# Exits non-zero on any failure.
set -euo pipefail
cd "$(dirname "$0")/../.."

missing=()
command -v chromium >/dev/null || missing+=(chromium)
command -v node >/dev/null || missing+=(nodejs)
command -v npm >/dev/null || missing+=(npm)
if [ ${#missing[@]} -gt 0 ]; then
    apt-get update -qq
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq "${missing[@]}"
fi
(cd tools/web && npm ci --no-audit --no-fund --loglevel=error)

cargo build --release
irid="$PWD/target/release/irid"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT

# Five exports: a free-standing film with the 16-bit PNGs (the page reads
# them first; the test also reads its EXRs; one chart for both sides), an
# absorbing film on gold (opaque), a film seen from its dense side (the
# warped angle axis), coated glass (a back side with total internal
# reflection) and a film on copper (opaque though it transmits into the
# metal; with the rough table, --rough, for the roughness control and the
# three.js module's rough lookup). The test compares each one's charts with
# `irid color` on its stack file, and the back sides' with the reversed stack.
"$irid" export luts/soap-film.toml --thickness 100:1000 --png -o "$work/soap-film" --quiet
"$irid" export luts/two-layer.toml --layer 1 --thickness 50:600 -o "$work/two-layer" --quiet
"$irid" export tools/web/dense-side.toml --thickness 100:800 -o "$work/dense-side" --quiet
"$irid" export tests/blender/film-on-glass.toml --thickness 100:800 -o "$work/film-on-glass" --quiet
"$irid" export tests/blender/film-on-copper.toml --thickness 100:500 --rough -o "$work/film-on-copper" --quiet
"$irid" preview "$work/soap-film" "$work/two-layer" "$work/dense-side" "$work/film-on-glass" \
    "$work/film-on-copper" -o "$work/preview"

IRID_PREVIEW="$work/preview" IRID_BIN="$irid" \
    IRID_STACKS="soap-film=luts/soap-film.toml,two-layer=luts/two-layer.toml,dense-side=tools/web/dense-side.toml,film-on-glass=tests/blender/film-on-glass.toml,film-on-copper=tests/blender/film-on-copper.toml" \
    node --test tools/web/test_web.mjs tools/web/test_three.mjs
