#!/usr/bin/env bash
# CI for the Python package (python/): installs it into a virtualenv (the
# wheel of tools/python_wheel.sh), installs the independent
# implementations the tests compare with (Byrnes' tmm, tmm-faster, mpmath for
# the 50-digit oracle of the derivatives; jax (CPU) for irid.autodiff), builds the
# irid CLI the tests compare with, and runs the pytest suite. Idempotent;
# exits non-zero on any failure, including a run that collects no tests.
set -euo pipefail
cd "$(dirname "$0")/../.."

venv=.venv-python
pip=(--quiet --disable-pip-version-check)
[ -x "$venv/bin/python" ] || python3 -m venv "$venv"
# dask[distributed]: the batched fit under a local Dask cluster (test_fit.py).
"$venv/bin/pip" install "${pip[@]}" pytest numpy mpmath jax tmm==0.2.0 tmm-faster==0.1.3 "dask[distributed]==2026.11.0"
# The wheel tools/test.sh built ($IRID_WHEEL), or one built here;
# --force-reinstall: the version number does not change with the sources.
wheel=$(bash tools/python_wheel.sh "$venv/bin/python")
"$venv/bin/pip" install "${pip[@]}" --force-reinstall --no-deps "$wheel"

cargo build --release --bin irid
export IRID_BIN="$PWD/target/release/irid" IRID_REQUIRE_CLI=1

# From the repository root, so that `import irid` finds the installed
# package, not the source folder python/irid (which lacks the extension).
status=0
"$venv/bin/pytest" -q python/tests || status=$?
if [ "$status" -eq 5 ]; then
    echo "python.sh: pytest collected no tests" >&2
fi
exit "$status"
