#!/usr/bin/env bash
# Byte-identity of everything irid writes from the stacks in luts/: tables
# (rgb and spectral, atlas and grid, the shipped tables' own ranges, a rough
# table), GPU exports (textures, PNGs, film.json, shaders, a rough export)
# and `irid validate --json`. For refactorings that must not change
# behaviour: record the outputs of a binary built before the change, then
# check the binary built after it against them.
#
#   tests/identical/run.sh BIN OUT            # writes OUT/ and OUT/SHA256SUMS
#   tests/identical/run.sh BIN OUT REF        # and compares with REF/SHA256SUMS
#
# e.g. tests/identical/run.sh ../main/target/release/irid /tmp/before
#      cargo build --release && tests/identical/run.sh target/release/irid /tmp/after /tmp/before
#
# Not part of tools/test.sh: it bakes about thirty tables and exports
# (minutes on two cores), and it compares two binaries, not one with itself.
# Outputs name "tool": "irid <version>", so compare binaries of one version.
set -euo pipefail
cd "$(dirname "$0")/../.."

if [ $# -lt 2 ] || [ $# -gt 3 ]; then
    sed -n '2,14p' "$0" | sed 's/^# \{0,1\}//' >&2
    exit 2
fi
bin=$(realpath "$1")
out=$2
ref=${3:-}
rm -rf "$out"
mkdir -p "$out"/bake "$out"/export "$out"/validate

run() { "$bin" "$@" >/dev/null 2>&1 || { echo "failed: irid $*" >&2; exit 1; }; }

# Every stack with the defaults of bake and export (layer 1 at its own
# thickness, 0–89°).
for stack in luts/*.toml; do
    name=$(basename "$stack" .toml)
    run bake "$stack" -o "$out/bake/$name-default.exr"
    run export "$stack" -o "$out/export/$name-default"
done

# The shipped tables with the options they were baked with
# (docs/architecture.md, "Shipped tables"), and exports over the same ranges.
while read -r name opts; do
    # shellcheck disable=SC2086
    run bake "luts/$name.toml" -o "$out/bake/$name-shipped.exr" --half $opts
    # shellcheck disable=SC2086
    run export "luts/$name.toml" -o "$out/export/$name-range" $opts
    "$bin" validate "$out/bake/$name-shipped.exr" --json >"$out/validate/$name-shipped.json"
done <<'LIST'
soap-film --thickness 0:1000
oil-on-water --thickness 0:1000
absorbing-film --thickness 0:1000
gain-on-gold --thickness 200:300 --angles 0.2:1
two-layer --thickness 0:600
mirror-10 --thickness 0:200
LIST

# The other paths through the bakers and the export.
run export luts/soap-film.toml -o "$out/export/soap-film-rough" --thickness 0:1000 --rough --png
run export luts/oil-on-water.toml -o "$out/export/oil-on-water-e-front" --thickness 0:1000 \
    --white e --front-only --sampling uniform:41
run bake luts/soap-film.toml -o "$out/bake/soap-film-rough.exr" --thickness 0:1000 --rough
run bake luts/soap-film.toml -o "$out/bake/soap-film-spectral.exr" --thickness 0:500 --angles 0.2:1 \
    --kind spectral
run bake luts/two-layer.toml -o "$out/bake/two-layer-spectral-grid.exr" --thickness 0:600 \
    --kind spectral --resolution 64,32,41
run bake luts/soap-film.toml -o "$out/bake/soap-film-grid.exr" --thickness 0:1000 --layout grid
run bake luts/oil-on-water.toml -o "$out/bake/oil-on-water-de.exr" --thickness 0:1000 --max-de 0.5
run bake luts/absorbing-film.toml -o "$out/bake/absorbing-film-fixed.exr" --thickness 0:1000 \
    --resolution 65,33 --no-check
"$bin" validate "$out/bake/soap-film-grid.exr" --json >"$out/validate/soap-film-grid.json"

(cd "$out" && find . -type f ! -name SHA256SUMS -print0 | sort -z | xargs -0 sha256sum) \
    >"$out/SHA256SUMS"
echo "$(wc -l <"$out/SHA256SUMS") files hashed in $out/SHA256SUMS"
if [ -n "$ref" ]; then
    if diff "$ref/SHA256SUMS" "$out/SHA256SUMS"; then
        echo "identical to $ref"
    else
        echo "DIFFERENT from $ref (lines above: < $ref, > $out)" >&2
        exit 1
    fi
fi
