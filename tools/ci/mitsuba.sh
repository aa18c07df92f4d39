#!/usr/bin/env bash
# CI: irid's irid_film BSDF in Mitsuba 3 (docs/mitsuba.md). Installs what is
# missing (Debian's libllvm19 for Mitsuba's llvm variants: the image's LLVM 15
# aborts with "Cannot select: fminimum"; a virtualenv with mitsuba, numpy,
# pytest and colour-science; the irid package from tools/python_wheel.sh), then runs
# python/tests_mitsuba. Idempotent; exits non-zero on any failure, including
# a run that collects no tests.
set -euo pipefail
cd "$(dirname "$0")/../.."

if ! ldconfig -p | grep -q 'libLLVM.so.19'; then
    apt-get update -qq
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq libllvm19
fi

venv=.venv-mitsuba
pip=(--quiet --disable-pip-version-check)
[ -x "$venv/bin/python" ] || python3 -m venv "$venv"
"$venv/bin/pip" install "${pip[@]}" "mitsuba==3.9.1" "drjit==1.5.0" numpy pytest "colour-science==0.4.7"
# The wheel tools/test.sh built ($IRID_WHEEL), or one built here;
# --force-reinstall: the version number does not change with the sources.
wheel=$(bash tools/python_wheel.sh "$venv/bin/python")
"$venv/bin/pip" install "${pip[@]}" --force-reinstall --no-deps "$wheel"

# Dr.Jit looks for libLLVM.so first; point it at version 19 explicitly.
llvm=$(ldconfig -p | awk '/libLLVM.so.19/ {print $NF; exit}')
export DRJIT_LIBLLVM_PATH="$llvm"

# From the repository root, so that `import irid` finds the installed
# package, not the source folder python/irid (which lacks the extension).
status=0
"$venv/bin/pytest" -q -p no:cacheprovider python/tests_mitsuba || status=$?
if [ "$status" -eq 5 ]; then
    echo "mitsuba.sh: pytest collected no tests" >&2
fi
exit "$status"
