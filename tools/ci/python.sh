#!/usr/bin/env bash
# CI for the Python package (python/): installs it into a virtualenv (the
# wheel of tools/python_wheel.sh), installs the independent
# implementations the tests compare with (Byrnes' tmm, tmm-faster, mpmath for
# the 50-digit oracle of the derivatives; jax (CPU) for irid.autodiff), builds the
# irid CLI the tests compare with, and runs the pytest suite. Then runs
# test_autodiff.py once more under Debian's CPU-only PyTorch (python3-torch,
# through apt-get as root when missing; PyPI's torch wheel drags in the GPU
# libraries): it is built for Debian's own python3 and numpy 1.24, so it gets
# a second virtualenv on /usr/bin/python3 with --system-site-packages.
# Idempotent; exits non-zero on any failure, including a run that collects no
# tests or a torch that does not import.
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
[ "$status" -eq 0 ] || exit "$status"

# irid.autodiff.torch_solve under Debian's torch. The wheel is CPython 3.11's,
# as is Debian bookworm's python3.
if ! /usr/bin/python3 -c "import torch, pytest" 2>/dev/null; then
    apt-get update -qq
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq python3-torch python3-pytest python3-venv >/dev/null
fi
torch_venv=.venv-python-torch
[ -x "$torch_venv/bin/python" ] || /usr/bin/python3 -m venv --system-site-packages "$torch_venv"
"$torch_venv/bin/pip" install "${pip[@]}" --force-reinstall --no-deps "$wheel"
IRID_REQUIRE_TORCH=1 "$torch_venv/bin/python" -m pytest -q -p no:cacheprovider python/tests/test_autodiff.py -k torch
