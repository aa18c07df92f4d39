#!/usr/bin/env bash
# Prints the path of a wheel of the irid Python package (python/) built from
# this checkout, building it only when needed, so that the scripts that
# install the package (tools/ci/python.sh, tools/ci/mitsuba.sh) share one
# build in a CI run instead of each compiling the extension.
#
#   bash tools/python_wheel.sh PYTHON
#
# PYTHON is an interpreter with pip (a virtualenv's), used to build the
# wheel (pip wheel runs maturin, from PyPI, in an isolated environment).
# When $IRID_WHEEL names an existing file, that wheel is printed and nothing
# is built: tools/test.sh builds once and exports it. Otherwise the wheel is
# built into a fresh folder under target/wheels/ (the previous one removed,
# so an older wheel of the same version number is never picked up). Build output
# goes to stderr; stdout is the path alone.
set -euo pipefail
cd "$(dirname "$0")/.."

if [ $# -ne 1 ]; then
    echo "usage: bash tools/python_wheel.sh PYTHON" >&2
    exit 2
fi
python=$1

if [ -n "${IRID_WHEEL:-}" ]; then
    if [ ! -f "$IRID_WHEEL" ]; then
        echo "python_wheel.sh: IRID_WHEEL: no such file: $IRID_WHEEL" >&2
        exit 2
    fi
    echo "$IRID_WHEEL"
    exit 0
fi

mkdir -p target/wheels
rm -rf target/wheels/build.*
out=$(mktemp -d "$PWD/target/wheels/build.XXXXXX")
"$python" -m pip wheel --quiet --disable-pip-version-check --no-deps -w "$out" ./python >&2
wheels=("$out"/irid-*.whl)
if [ ${#wheels[@]} -ne 1 ] || [ ! -f "${wheels[0]}" ]; then
    echo "python_wheel.sh: expected one irid wheel in $out, found: ${wheels[*]}" >&2
    exit 1
fi
echo "${wheels[0]}"
