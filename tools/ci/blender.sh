#!/usr/bin/env bash
# CI: irid in Blender (docs/blender.md), the add-on in blender/irid_blender.
# Installs what is missing (the X libraries Blender's Python module links
# against, EGL and Mesa's software rasteriser for EEVEE, a Python 3.11
# virtualenv with bpy 5.0, numpy < 2 and OpenEXR, the irid binary), then
# runs the tests in blender/tests: test_film_json.py (the film.json reader
# rule over tests/film-json), test_docs.py (docs/blender.md's snippets as
# written), test_blender.py (Cycles renders of irid exports against `irid
# color`), test_eevee.py (EEVEE against Cycles: no seam at chart borders,
# no speckles at the rim), test_metallic.py (Cycles' Metallic BSDF thin
# film, for the docs' comparison) and test_rough_cycles.py (Cycles' rough
# thin film and irid's material on `irid export --rough` exports against
# `irid color --roughness`). Idempotent; exits non-zero on any failure.
set -euo pipefail
cd "$(dirname "$0")/../.."

# bpy's wheel carries its own libraries but links these from the system.
missing=()
for lib in libX11.so.6:libx11-6 libXrender.so.1:libxrender1 libXfixes.so.3:libxfixes3 \
           libXi.so.6:libxi6 libxkbcommon.so.0:libxkbcommon0 \
           libEGL.so.1:libegl1 libEGL_mesa.so.0:libegl-mesa0; do
    ldconfig -p | grep "${lib%%:*}" >/dev/null || missing+=("${lib##*:}")
done
# EEVEE draws through EGL; with no GPU, on Mesa's software rasteriser.
ls /usr/lib/*/dri/swrast_dri.so >/dev/null 2>&1 || missing+=(libgl1-mesa-dri)
if [ "${#missing[@]}" -gt 0 ]; then
    apt-get update -qq
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq "${missing[@]}"
fi

# bpy 5.0 ships wheels for CPython 3.11 only.
python=""
for candidate in python3.11 python3; do
    if command -v "$candidate" >/dev/null &&
        "$candidate" -c 'import sys; sys.exit(sys.version_info[:2] != (3, 11))'; then
        python="$candidate"
        break
    fi
done
if [ -z "$python" ]; then
    echo "tools/ci/blender.sh: bpy 5.0 needs Python 3.11, none found" >&2
    exit 2
fi
venv=.venv-blender
if ! "$venv/bin/python" -c 'import bpy, numpy, OpenEXR' 2>/dev/null; then
    "$python" -m venv "$venv"
    "$venv/bin/pip" install --quiet --disable-pip-version-check \
        "bpy==5.0.*" "numpy<2" "OpenEXR==3.5.3"
fi

cargo build --release --quiet --bin irid
"$venv/bin/python" blender/tests/test_film_json.py
"$venv/bin/python" blender/tests/test_docs.py --irid target/release/irid
"$venv/bin/python" blender/tests/test_blender.py --irid target/release/irid \
    --table "$(mktemp -d)/blender-table.md"
"$venv/bin/python" blender/tests/test_eevee.py --irid target/release/irid
"$venv/bin/python" blender/tests/test_metallic.py --irid target/release/irid
# Cycles' own rough thin film (docs/rough.md) and irid's material with the
# rough table (docs/blender.md) against `irid color --roughness`.
"$venv/bin/python" blender/tests/test_rough_cycles.py --irid target/release/irid
