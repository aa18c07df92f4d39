"""Shared helpers: the repository's paths and the irid command-line tool.

Tests that compare with the CLI need the `irid` binary: $IRID_BIN, or
target/release/irid of this repository (`cargo build --release`). Without it
they are skipped, unless IRID_REQUIRE_CLI=1 (CI) makes that a failure.
"""

import os
import shutil
import subprocess
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
LUTS = REPO / "luts"


def cli_path():
    candidates = [os.environ.get("IRID_BIN"), str(REPO / "target" / "release" / "irid"), shutil.which("irid")]
    for c in candidates:
        if c and os.path.isfile(c) and os.access(c, os.X_OK):
            return c
    return None


@pytest.fixture(scope="package")
def irid_cli():
    """Runs the irid CLI: irid_cli(*args) -> CompletedProcess (text)."""
    path = cli_path()
    if path is None:
        message = "the irid CLI is needed: set IRID_BIN or run `cargo build --release`"
        if os.environ.get("IRID_REQUIRE_CLI") == "1":
            pytest.fail(message)
        pytest.skip(message)

    def run(*args):
        return subprocess.run([path, *map(str, args)], capture_output=True, text=True)

    return run


@pytest.fixture(scope="package")
def luts():
    if not LUTS.is_dir():
        pytest.skip("needs the repository's luts/ folder (run from a clone)")
    return LUTS
