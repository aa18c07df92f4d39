"""Fixtures of the irid_film tests (the shared set-up is mitsuba_setup.py)."""

import pytest

from mitsuba_setup import JIT, dr, mi, use


@pytest.fixture
def jit():
    use(JIT)
    yield
    mi.set_variant(JIT)
    dr.set_flag(dr.JitFlag.SymbolicLoops, True)
    dr.set_flag(dr.JitFlag.SymbolicCalls, True)
