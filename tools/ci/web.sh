#!/usr/bin/env bash
# CI: the browser preview (web/) in headless Chromium. Installs what is
# missing (Debian's chromium, node and npm; playwright-core from
# tools/web/package-lock.json), builds irid, exports two stacks, writes a
# preview of them with `irid preview`, and runs tools/web/test_web.mjs.
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

# The first export is the one the test checks against `irid color`; the
# second (a film on gold, opaque) gives the page's export menu a choice.
"$irid" export luts/soap-film.toml --thickness 100:1000 --png -o "$work/soap-film" --quiet
"$irid" export luts/two-layer.toml --layer 1 --thickness 50:600 -o "$work/two-layer" --quiet
"$irid" preview "$work/soap-film" "$work/two-layer" -o "$work/preview"

IRID_PREVIEW="$work/preview" IRID_STACK="$PWD/luts/soap-film.toml" IRID_BIN="$irid" \
    node --test tools/web/test_web.mjs
