"""Every entry point estimates what it will allocate before allocating it and
raises MemoryError above the library's memory budget (IRID_MEMORY_LIMIT, else
half the machine's memory), instead of aborting the interpreter."""

import os

import numpy as np
import pytest

import irid

#: A stride-0 view: a huge array that costs no memory until it is copied.
HUGE = 10**13


def huge(value):
    return np.broadcast_to(np.float64(value), (HUGE,))


@pytest.fixture
def limit(monkeypatch):
    """Sets IRID_MEMORY_LIMIT for the test (read by the library at each call)."""

    def set_limit(text):
        monkeypatch.setenv("IRID_MEMORY_LIMIT", text)

    monkeypatch.delenv("IRID_MEMORY_LIMIT", raising=False)
    return set_limit


def default_budget():
    """The library's default: half of physical memory (or of the control
    group's limit when lower)."""
    memory = os.sysconf("SC_PHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
    try:
        with open("/sys/fs/cgroup/memory.max") as f:
            memory = min(memory, int(f.read().strip()))
    except (OSError, ValueError):
        pass
    return memory // 2


def grid_args(wavelengths, angles):
    w = np.linspace(400.0, 700.0, wavelengths)
    return [1.0, 1.5, 1.0], [np.inf, 100.0, np.inf], np.zeros(angles), w


def test_the_48_gb_coherent_request_of_the_issue_raises(limit):
    # 10^4 wavelengths × 10^5 angles × 6 results × 8 bytes = 48 GB: this
    # aborted the interpreter ("memory allocation of 48000000000 bytes failed").
    if default_budget() >= 48e9:
        pytest.skip("this machine's default budget covers 48 GB")
    with pytest.raises(MemoryError, match=r"needs about 4[89]\.\d GB, above the memory limit"):
        irid.coherent(*grid_args(10**4, 10**5))


def test_coherent_honours_irid_memory_limit(limit):
    args = grid_args(10**3, 10**4)  # a 480 MB result
    limit("100M")
    with pytest.raises(MemoryError) as e:
        irid.coherent(*args)
    assert "1000 wavelengths × 10000 angles × 3 media: needs about 4" in str(e.value)
    assert "above the memory limit of 104.9 MB (set IRID_MEMORY_LIMIT" in str(e.value)
    # A 48 MB result is within the same limit.
    assert irid.coherent(*grid_args(10**3, 10**3))["R_avg"].shape == (10**3, 10**3)


def test_coherent_counts_a_shared_index_row_repeated_per_wavelength(limit):
    # A 1-D n is repeated for every wavelength: 4000 media × 10^4
    # wavelengths of complex indices is 640 MB before any result.
    n = np.full(4000, 1.5 + 0j)
    n[0] = 1.0
    d = np.full(4000, 1.0)
    d[0] = d[-1] = np.inf
    limit("100M")
    with pytest.raises(MemoryError, match="media"):
        irid.coherent(n, d, [0.0], np.linspace(400, 700, 10**4))


def film():
    return irid.Stack(layers=[(1.33, 300.0)], substrate=1.5)


@pytest.mark.parametrize(
    "name, call",
    [
        ("Stack.solve", lambda: film().solve(np.linspace(400, 700, 1000), np.zeros(1000))),
        ("Stack.solve over thicknesses", lambda: film().solve([500.0] * 100, [0.0] * 100, thickness_nm=np.zeros(100))),
        ("Stack.color", lambda: film().color(np.zeros(10**4))),
        ("Material.index", lambda: irid.material("gold").index(np.full(10**7, 500.0))),
        ("bake", lambda: irid.bake(film(), resolution=(1024, 1024), validation_points=0)),
        ("Lut.sample", lambda: SMALL_LUT.sample(np.zeros(10**7), 1.0)),
        ("Stack.response", lambda: film().response(np.zeros((10**3, 1)), np.full(10**4, 500.0))),
    ],
)
def test_each_entry_point_honours_irid_memory_limit(limit, name, call):
    limit("100M")
    with pytest.raises(MemoryError, match="above the memory limit of 104.9 MB"):
        call()


SMALL_LUT = irid.bake(film(), thickness_nm=(0, 600), resolution=(8, 4), validation_points=0)


def test_loading_a_table_honours_irid_memory_limit(limit, tmp_path):
    path = tmp_path / "t.exr"
    SMALL_LUT.save(path)
    limit("1K")
    with pytest.raises(MemoryError, match="t.exr: loading the table: needs about"):
        irid.Lut.load(path)
    limit("1M")
    assert irid.Lut.load(path).data.shape == (4, 8, 6)


@pytest.mark.parametrize(
    "name, call",
    [
        ("coherent angles", lambda: irid.coherent([1.0, 1.5], [np.inf, np.inf], huge(0.0), [500.0])),
        ("coherent wavelengths", lambda: irid.coherent([1.0, 1.5], [np.inf, np.inf], [0.0], huge(500.0))),
        ("Stack.solve", lambda: film().solve(huge(500.0), [0.0])),
        ("Stack.color", lambda: film().color(huge(0.0))),
        ("Material.index", lambda: irid.material("gold").index(huge(500.0))),
        ("Lut.sample", lambda: SMALL_LUT.sample(huge(100.0), 1.0)),
        ("Lut.sample broadcast", lambda: SMALL_LUT.sample(np.zeros((10**7, 1)), np.zeros(10**7))),
    ],
)
def test_huge_views_are_refused_before_they_are_copied(limit, name, call):
    # Under the default budget: each would copy terabytes.
    with pytest.raises(MemoryError, match="above the memory limit"):
        call()


def test_a_malformed_limit_is_a_value_error(limit):
    limit("lots")
    with pytest.raises(ValueError, match="IRID_MEMORY_LIMIT: 'lots' is not a size in bytes"):
        irid.coherent(*grid_args(3, 2))


def test_copying_a_tables_data_honours_irid_memory_limit(limit):
    lut = irid.bake(film(), thickness_nm=(0, 600), resolution=(64, 16), validation_points=0)
    limit("16K")  # the copy is 64 × 16 × 6 float32: 24.6 kB
    with pytest.raises(MemoryError, match="data: a copy of 6144 values: needs about 24.6 kB"):
        lut.data
    limit("32K")
    assert lut.data.shape == (16, 64, 6)


def test_reading_a_stack_file_or_index_table_honours_irid_memory_limit(limit, tmp_path):
    big = tmp_path / "big.toml"
    big.write_bytes(b"#" * (2 << 20))
    limit("1M")
    with pytest.raises(MemoryError, match=r"big.toml: reading the file: needs about 2\.1 MB, above"):
        irid.Stack.load(big)
    # A file whose size the system does not give is cut off at the budget.
    with pytest.raises(MemoryError, match="/dev/zero: reading the file: holds more than the memory limit of 1.0 MB"):
        irid.Stack.load("/dev/zero")
    with pytest.raises(MemoryError, match="substrate.table: /dev/zero: reading the file: holds more than"):
        irid.Stack(substrate={"table": "/dev/zero"})


def test_baking_to_an_error_target_honours_irid_memory_limit(limit):
    # The refinement checks each round's grid as it grows.
    limit("2M")
    with pytest.raises(MemoryError, match=r"max-error 1e-5: a grid of \d+ nodes checked at \d+: needs about"):
        irid.bake(film(), max_error=1e-5, validation_points=0)


#: Runs CALL in a child interpreter (with `np` and `irid` imported) and
#: prints the exception it raised, or "ok", then the growth of the child's
#: peak resident memory over the call, in MB.
CHILD = """
import resource, sys
import numpy as np
import irid

before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
try:
    {call}
    outcome = "ok"
except MemoryError as e:
    outcome = "MemoryError: " + str(e)
grown = (resource.getrusage(resource.RUSAGE_SELF).ru_maxrss - before) / 1024
print(outcome)
print(round(grown))
"""


def run_child(call, *, env=None, address_space=None):
    """(what the call raised or "ok", its peak memory growth in MB) in a
    child interpreter; `address_space` caps the child's RLIMIT_AS, as
    `ulimit -v` or `prlimit --as` do."""
    import resource
    import subprocess
    import sys

    def cap():
        if address_space is not None:
            resource.setrlimit(resource.RLIMIT_AS, (address_space, address_space))

    child_env = {k: v for k, v in os.environ.items() if k != "IRID_MEMORY_LIMIT"}
    child_env.update(env or {})
    run = subprocess.run(
        [sys.executable, "-c", CHILD.format(call=call)],
        capture_output=True,
        text=True,
        env=child_env,
        preexec_fn=cap,
        timeout=300,
    )
    assert run.returncode == 0, f"exit {run.returncode}: {run.stderr.strip()[-500:]}"
    outcome, grown = run.stdout.strip().rsplit("\n", 1)
    return outcome, int(grown)


ISSUE_GRID = "irid.coherent(np.array([1, 1.5, 1.0]), [np.inf, 100, np.inf], np.linspace(0, 89, 15000), np.linspace(400, 700, 10**4))"


@pytest.mark.parametrize("env", [{}, {"IRID_MEMORY_LIMIT": "1T"}])
def test_an_address_space_limit_is_a_memory_error_not_an_abort(env):
    # The issue's case: a 7.2 GB result under a 6 GiB RLIMIT_AS aborted the
    # interpreter ("memory allocation of 7200000000 bytes failed", SIGABRT),
    # as it did with any IRID_MEMORY_LIMIT above what the limit leaves.
    outcome, _ = run_child(ISSUE_GRID, env=env, address_space=6 << 30)
    assert outcome.startswith(
        "MemoryError: 10000 wavelengths × 15000 angles × 3 media: needs about 7.2 GB, above the memory limit of"
    ), outcome
    assert outcome.endswith("(what the process's address-space limit, ulimit -v, leaves free)"), outcome
    # What fits under the same limit runs.
    outcome, _ = run_child(
        "irid.coherent([1, 1.5, 1.0], [np.inf, 100, np.inf], np.linspace(0, 89, 1000), np.linspace(400, 700, 10**4))",
        address_space=6 << 30,
    )
    assert outcome == "ok"


#: 2·10^8 values of a stride-0 view: a 1.6 GB copy.
MANY = "np.broadcast_to({}, (2 * 10**8,))"


@pytest.mark.parametrize(
    "name, call, counted",
    [
        ("Stack.color", f"irid.Stack(layers=[(1.5, 300.0)]).color({MANY.format(30.0)})", "200000000 angles"),
        (
            "Stack.color rough",
            f"irid.Stack(layers=[(1.5, 300.0)]).color({MANY.format(30.0)}, roughness=0.3)",
            "200000000 angles",
        ),
        (
            "Stack.color gradient",
            f"irid.Stack(layers=[(1.5, 300.0)]).color({MANY.format(30.0)}, gradient=True)",
            "200000000 angles",
        ),
        (
            "Stack.solve index gradient",
            f"irid.Stack(layers=[(1.5, 300.0)]).solve([500.0], {MANY.format(0.0)}, gradient=True, index_gradient=True)",
            "200000000 angles",
        ),
        ("Stack.solve angles", f"irid.Stack(layers=[(1.5, 300.0)]).solve([500.0], {MANY.format(0.0)})", "200000000 angles"),
        (
            "Stack.solve wavelengths",
            f"irid.Stack(layers=[(1.5, 300.0)]).solve({MANY.format(500.0)}, [0.0])",
            "200000000 wavelengths",
        ),
        (
            "coherent",
            f"irid.coherent([1, 1.5, 1.0], [np.inf, 100, np.inf], {MANY.format(0.0)}, [500.0])",
            "200000000 angles",
        ),
        (
            "incoherent",
            f"irid.incoherent([1, 1.5, 1.0], [np.inf, 100, np.inf], 'ici', {MANY.format(0.0)}, [500.0])",
            "200000000 angles",
        ),
        (
            "fit",
            f"irid.fit(irid.Stack(layers=[(1.5, 300.0)]), [1], {MANY.format(500.0)}, [0.0], R=np.broadcast_to(0.5, (2 * 10**8, 1)))",
            "200000000 measured values",
        ),
        (
            "fit_color",
            f"irid.fit_color(irid.Stack(layers=[(1.5, 300.0)]), [1], {MANY.format(0.0)}, np.broadcast_to(0.5, (2 * 10**8, 3)))",
            "200000000 angles",
        ),
    ],
)
def test_the_budget_is_checked_before_the_arguments_are_copied(name, call, counted):
    # 2·10^8 angles copy into 1.6 GB, within a 2 GiB limit, but the call's
    # results and buffers are far above it: refused before the copy.
    outcome, grown = run_child(call, env={"IRID_MEMORY_LIMIT": "2G"})
    assert outcome.startswith("MemoryError: ") and counted in outcome, outcome
    assert grown < 200, f"{name}: the peak memory grew by {grown} MB before the MemoryError"


def test_the_index_gradient_counts_its_arrays(limit):
    # 20 layers × 10^5 points: the thickness gradient's arrays fit in
    # 400 MB, the 20 more per layer by n and k (solved and returned) do not.
    stack = irid.Stack(layers=[(1.45, 95.0), (2.3, 60.0)] * 10, substrate=1.52)
    wavelengths, angles = np.linspace(400.0, 700.0, 1000), np.linspace(0.0, 80.0, 100)
    limit("400M")
    assert stack.solve(wavelengths, angles, gradient=True)["dR_dd"].shape == (20, 1000, 100)
    with pytest.raises(MemoryError, match=r"the gradient of 20 layers × 1000 wavelengths × 100 angles: needs about 566"):
        stack.solve(wavelengths, angles, gradient=True, index_gradient=True)
