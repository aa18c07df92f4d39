#!/usr/bin/env bash
# The whole test suite, exactly as CI runs it (.ci/run calls this script).
#
# On a fresh Debian machine with only the Rust toolchain, Python 3.11 with
# pip, and gcc, it installs what the checks need before running them: Python
# virtualenvs under .venv*/ (from PyPI), and, through apt-get as root, the
# Debian packages a check needs (the software Vulkan driver, Chromium, the X
# libraries Blender's Python module links, the CPU-only PyTorch the autodiff
# test uses). Each step exits non-zero on a
# failure and the script stops at the first one.
set -euo pipefail
cd "$(dirname "$0")/.."

step() { printf '\n== %s\n' "$*"; }

step "cargo fmt --check"
cargo fmt --check

step "tools/check_links.py (every relative link and anchor in the Markdown)"
python3 tools/check_links.py

# No hand-written source file over 900 lines, no Rust function over 100
# (files marked @generated are skipped), in every language it reads.
step "tools/check_sizes.py"
python3 tools/check_sizes.py

step "cargo test --release"
cargo test --release

# The library alone (no `cli` feature, so no bench either), as a dependent
# with default-features = false builds it; the tests that run the binary
# or use the bench are gated on those features.
step "cargo test --release --no-default-features"
cargo test --release --no-default-features

# Cross-checks against independent Python implementations (tmm,
# colour-science, OpenEXR, tmm-faster), in a virtualenv made here.
step "Python cross-checks"
python3 -m venv .venv
.venv/bin/pip install --quiet --disable-pip-version-check -r tools/requirements.txt
export IRID_BIN="$PWD/target/release/irid"
for check in tools/crosscheck/crosscheck_*.py tools/crosscheck/read_lut.py; do
    step "$check"
    .venv/bin/python "$check"
done

# irid against tmm, colour-science and tmm-faster on the same grids: fails if
# irid and Byrnes' tmm disagree beyond 1e-9. The committed figures in
# benches/results/ come from a developer's run; this one writes elsewhere.
step "tools/bench/bench_peers.py"
OMP_NUM_THREADS=2 .venv/bin/python tools/bench/bench_peers.py -o "$(mktemp -d)"

# The Python package's extension, compiled once for the scripts that
# install it (python.sh, mitsuba.sh); each builds its own when run alone.
step "tools/python_wheel.sh"
IRID_WHEEL=$(bash tools/python_wheel.sh .venv/bin/python)
export IRID_WHEEL
echo "$IRID_WHEEL"

# One script per integration (GPU shaders on lavapipe, the Python package,
# the browser preview, Blender), each installing what it needs.
for script in tools/ci/*.sh; do
    [ -e "$script" ] || continue
    step "$script"
    bash "$script"
done
