"""irid.incoherent and Stack.solve on stacks with incoherent (thick) layers,
against Byrnes' tmm.inc_tmm (the reference, 1e-9) and tmm-faster's
calc_incoherent (the API it replaces: same keys and shapes; same values
where tmm-faster is right); the limits; and tmm-faster's own example run
with irid in its place."""

import math
import os
import re
import runpy
import sys
import types

import numpy as np
import pytest
import tmm
import tmm_faster

import irid

TOL = 1e-9
KEYS = ["R_s", "R_p", "T_s", "T_p", "R_avg", "T_avg"]


def byrnes(n, d, c, angles_deg, wavelengths_nm):
    """Byrnes' inc_tmm at every point, in calc_incoherent's layout."""
    out = {k: np.empty((len(wavelengths_nm), len(angles_deg))) for k in KEYS}
    for i, w in enumerate(wavelengths_nm):
        for j, a in enumerate(angles_deg):
            for pol in "sp":
                res = tmm.inc_tmm(pol, list(n[i]), list(d), list(c), math.radians(a), w)
                out["R_" + pol][i, j], out["T_" + pol][i, j] = res["R"], res["T"]
    out["R_avg"] = 0.5 * (out["R_s"] + out["R_p"])
    out["T_avg"] = 0.5 * (out["T_s"] + out["T_p"])
    return out


def max_diff(a, b):
    return max(float(np.max(np.abs(a[k] - b[k]))) for k in KEYS)


def random_mixed(rng, layers, wavelengths=4, *, metals=True, absorbing=True):
    """A random stack with dispersive indices and at least one incoherent
    layer: incoherent layers lossless (above the ambient's index, so
    never evanescent), weakly or strongly absorbing; coherent layers
    lossless or absorbing; a lossless, lossy or metal substrate."""
    media = layers + 2
    n = np.empty((wavelengths, media), dtype=complex)
    ambient = rng.uniform(1.0, 1.6)
    n[:, 0] = ambient
    c = ["i"] + ["i" if rng.random() < 0.4 else "c" for _ in range(layers)] + ["i"]
    if "i" not in c[1:-1]:
        c[int(rng.integers(1, media - 1))] = "i"
    d = [np.inf]
    for j in range(1, media - 1):
        re = rng.uniform(ambient + 0.05 if c[j] == "i" else 1.0, 2.8, wavelengths)
        kind = rng.integers(3)
        if c[j] == "i":
            kind = kind if absorbing else 0
            im = [np.zeros(wavelengths), rng.uniform(0.0, 1e-4, wavelengths), rng.uniform(0.0, 0.3, wavelengths)][kind]
            d.append(float(10 ** rng.uniform(3.0, 6.0)))
        else:
            im = np.zeros(wavelengths) if kind == 0 else rng.uniform(0.0, 1.0, wavelengths)
            d.append(float(rng.uniform(0.0, 600.0)))
        n[:, j] = re + 1j * im
    kind = rng.integers(3) if metals else 0
    n[:, -1] = [complex(rng.uniform(1.0, 2.5)), complex(rng.uniform(1.0, 2.5), rng.uniform(0.0, 0.5)),
                complex(rng.uniform(0.05, 2.0), rng.uniform(1.0, 8.0))][kind]
    d.append(np.inf)
    w = np.sort(rng.uniform(300.0, 1000.0, wavelengths))
    return n, d, c, w


# Up to 89 degrees: nearer grazing, inc_tmm's Snell angles through absorbing
# media pick up imaginary parts and its forward-wave test asserts.
ANGLES = np.array([0.0, 20.0, 45.0, 60.0, 75.0, 85.0, 89.0])


@pytest.mark.parametrize("seed", range(12))
def test_random_mixed_stacks_match_byrnes(seed):
    rng = np.random.default_rng(seed)
    n, d, c, w = random_mixed(rng, int(rng.integers(1, 8)))
    got = irid.incoherent(n, d, c, ANGLES, w)
    assert max_diff(got, byrnes(n, d, c, ANGLES, w)) <= TOL


HARD = {
    # A film on each face of a millimetre of glass.
    "coated sheet": ([1.0, 2.3, 1.52, 1.38, 1.0], [np.inf, 80.0, 1e6, 100.0, np.inf], "icici"),
    # Several incoherent layers, metals between them, a metal substrate.
    "several": (
        [1.0, 1.52, 0.2 + 3.4j, 1.33 + 1e-6j, 2.1, 1.45, 0.05 + 4.0j],
        [np.inf, 1e6, 20.0, 5e5, 80.0, 2e6, np.inf],
        "iiciici",
    ),
    # A thick absorbing sheet, and a metal as an incoherent layer.
    "absorbing": ([1.0, 1.38, 1.6 + 2e-3j, 0.1 + 3.0j, 1.5], [np.inf, 100.0, 2e4, 3e3, np.inf], "iciii"),
    # tmm-faster's example stack.
    "tmm-faster example": (
        [1.0, 0.05 + 3.0j, 2.4 + 0.001j, 1.5, 2.4 + 0.001j, 1.0],
        [np.inf, 5.0, 500.0, 5e4, 200.0, np.inf],
        "iccici",
    ),
}


@pytest.mark.parametrize("case", sorted(HARD))
def test_hard_cases_match_byrnes_through_both_interfaces(case):
    n_list, d, c = HARD[case]
    w = np.linspace(380.0, 780.0, 9)
    n = np.tile(np.array(n_list, dtype=complex), (len(w), 1))
    angles = np.linspace(0.0, 89.9, 13)
    ref = byrnes(n, d, c, angles, w)
    assert max_diff(irid.incoherent(n, d, list(c), angles, w), ref) <= TOL
    # The same stack as an irid.Stack: R and T only (no amplitudes).
    stack = irid.Stack(
        ambient=n_list[0],
        layers=[(complex(m), t, flag == "c") for m, t, flag in zip(n_list[1:-1], d[1:-1], c[1:-1])],
        substrate=complex(n_list[-1]),
    )
    assert stack.coherent == [flag == "c" for flag in c[1:-1]]
    out = stack.solve(w, angles[:-1] if angles[-1] >= 90 else angles)
    assert sorted(out) == sorted(["R", "T", "Rs", "Rp", "Ts", "Tp"])
    for mine, theirs in [("Rs", "R_s"), ("Rp", "R_p"), ("Ts", "T_s"), ("Tp", "T_p")]:
        assert np.max(np.abs(out[mine] - ref[theirs])) <= TOL


def test_stack_file_and_stack_agree(tmp_path):
    """`coherent = false` in a stack file, the tuple flag and the dict key
    give the same stack."""
    text = (
        'ambient = { n = 1.0 }\nsubstrate = { n = 1.0 }\n'
        '[[layers]]\nn = 2.3\nthickness_nm = 80\n'
        '[[layers]]\nmaterial = "fused-silica"\nthickness_nm = 1e6\ncoherent = false\n'
    )
    a = irid.Stack.from_toml(text)
    b = irid.Stack(ambient=1.0, layers=[(2.3, 80.0), ("fused-silica", 1e6, False)], substrate=1.0)
    c = irid.Stack(layers=[{"n": 2.3, "thickness_nm": 80}, {"material": "fused-silica", "thickness_nm": 1e6, "coherent": False}])
    w, angles = np.linspace(400, 700, 7), [0.0, 50.0]
    for other in (b, c):
        assert other.coherent == a.coherent == [True, False]
        for k in ("R", "T"):
            assert np.array_equal(other.solve(w, angles)[k], a.solve(w, angles)[k])
    assert "False" in repr(b)


def test_same_keys_shapes_and_dtypes_as_tmm_faster():
    rng = np.random.default_rng(3)
    n, d, c, w = random_mixed(rng, 4, wavelengths=11)
    angles = np.linspace(0.0, 80.0, 5)
    mine = irid.incoherent(n, d, c, angles, w)
    theirs = tmm_faster.calc_incoherent(n, d, c, angles, w)
    assert isinstance(mine, dict)
    assert sorted(mine) == sorted(theirs) == sorted(KEYS)
    for k in KEYS:
        assert mine[k].shape == theirs[k].shape == (11, 5)
        assert mine[k].dtype == np.float64
    # c as tmm-faster takes it, or as any sequence of letters.
    for other in (tuple(c), np.array(c), "".join(c)):
        assert max_diff(irid.incoherent(n, d, other, angles, w), mine) == 0.0


def alternating(rng, sheets, wavelengths=20):
    """Coherent groups of 1-3 films alternating with lossless incoherent
    sheets, from the ambient down: the stacks tmm-faster 0.1.3 gets right
    (see test_right_where_tmm_faster_is_wrong)."""
    n_row, d, c = [1.0], [np.inf], ["i"]
    for sheet in range(sheets + 1):
        for _ in range(int(rng.integers(1, 4))):
            k = 0.0 if rng.random() < 0.5 else rng.uniform(0.0, 0.5)
            n_row.append(complex(rng.uniform(1.2, 2.6), k))
            d.append(float(rng.uniform(10.0, 400.0)))
            c.append("c")
        n_row.append(complex(rng.uniform(1.3, 2.0)))
        d.append(float(10 ** rng.uniform(3.0, 6.0)) if sheet < sheets else np.inf)
        c.append("i")
    n = np.tile(np.array(n_row, dtype=complex), (wavelengths, 1))
    return n, d, c, np.linspace(380.0, 780.0, wavelengths)


@pytest.mark.parametrize("seed", range(6))
def test_matches_tmm_faster_where_it_is_right(seed):
    """Coherent groups between lossless incoherent sheets, from the ambient
    down: tmm-faster agrees with Byrnes' inc_tmm there, and irid must agree
    with both."""
    rng = np.random.default_rng(50 + seed)
    n, d, c, w = alternating(rng, int(rng.integers(1, 4)))
    angles = np.linspace(0.0, 89.0, 15)
    mine = irid.incoherent(n, d, c, angles, w)
    assert max_diff(mine, tmm_faster.calc_incoherent(n, d, c, angles, w)) <= TOL


@pytest.mark.parametrize(
    "n_list, d, c",
    [
        # An absorbing substrate under an incoherent sheet: tmm-faster 0.1.3
        # takes Re(n conj(cos)) for s-polarized power there (Byrnes: Re(n cos)).
        ([1.0, 1.38, 1.5, 0.4 + 2.4j], [np.inf, 100.0, 1e6, np.inf], "icii"),
        # Two incoherent media in a row above a coherent group: tmm-faster
        # 0.1.3 takes the group's angle of incidence from the wrong medium
        # (it looks the group's top medium up by the group's number).
        ([1.0, 2.0, 1.38, 1.5], [np.inf, 1e5, 100.0, np.inf], "iici"),
    ],
)
def test_right_where_tmm_faster_is_wrong(n_list, d, c):
    w = np.linspace(400.0, 700.0, 7)
    n = np.tile(np.array(n_list, dtype=complex), (len(w), 1))
    angles = np.linspace(0.0, 85.0, 6)
    ref = byrnes(n, d, c, angles, w)
    assert max_diff(irid.incoherent(n, d, list(c), angles, w), ref) <= TOL
    assert max_diff(tmm_faster.calc_incoherent(n, d, list(c), angles, w), ref) > 1e-2


def test_limits():
    w = np.array([450.0, 633.0])
    angles = np.array([0.0, 45.0, 80.0, 90.0])
    # An opaque layer: P = e^(-2 k0 k d) underflows, T is exactly 0.
    n = np.tile(np.array([1.0, 1.38, 1.5 + 0.5j, 1.0], dtype=complex), (2, 1))
    out = irid.incoherent(n, [np.inf, 100.0, 1e7, np.inf], "icii", angles, w)
    assert np.all(out["T_s"] == 0.0) and np.all(out["T_p"] == 0.0)
    ref = byrnes(n, [np.inf, 100.0, 1e7, np.inf], "icii", angles[:-1], w)
    assert max(float(np.max(np.abs(out[k][:, :-1] - ref[k]))) for k in ("R_s", "R_p")) <= TOL
    # A zero-thickness incoherent sheet: its faces add in power.
    n = np.tile(np.array([1.0, 1.5, 1.0], dtype=complex), (2, 1))
    out = irid.incoherent(n, [np.inf, 0.0, np.inf], "iii", angles, w)
    r1 = (0.5 / 2.5) ** 2
    assert abs(out["R_avg"][0, 0] - 2 * r1 / (1 + r1)) < 1e-15
    # Grazing incidence: no power enters.
    assert np.all(out["R_avg"][:, -1] == 1.0) and np.all(out["T_avg"][:, -1] == 0.0)
    # From glass, a lossless incoherent layer beyond its critical angle is
    # opaque: it reflects as a half-space would (totally), T = 0.
    n = np.tile(np.array([1.5, 1.33, 1.5], dtype=complex), (2, 1))
    out = irid.incoherent(n, [np.inf, 2e4, np.inf], "iii", [70.0, 80.0], w)
    assert np.all(out["T_avg"] == 0.0) and np.all(np.abs(out["R_avg"] - 1.0) < 1e-15)


def test_a_lasing_layer_is_a_value_error():
    n = np.array([1.0, 1.5 - 0.01j, 1.5], dtype=complex)
    with pytest.raises(ValueError) as e:
        irid.incoherent(n, [np.inf, 1e6, np.inf], "iii", [0.0], [550.0])
    message = str(e.value)
    assert message.startswith("n[0, 1]: this incoherent layer lases at 550 nm") and "\n" not in message
    stack = irid.Stack(layers=[((1.5, -0.01), 1e6, False)], substrate=1.5)
    with pytest.raises(ValueError, match=r"^layers\[1\]: this incoherent layer lases"):
        stack.solve([550.0], [0.0])


def test_a_strong_gain_is_a_short_figure_in_the_lasing_error():
    # A 1 mm absorber-turned-amplifier: the power grows by e^500-odd per
    # round trip, a figure that printed in fixed point ran to hundreds of digits.
    with pytest.raises(ValueError) as e:
        irid.incoherent(np.array([1, 1.52 - 0.01j, 1.0]), [np.inf, 1e6, np.inf], "iii", [0.0], [500.0])
    message = str(e.value)
    assert len(message) < 250 and "\n" not in message, message
    gain = re.search(r"comes back with (\S+) times its power", message).group(1)
    assert re.fullmatch(r"\d\.\d\de\d+", gain), gain
    assert float(gain) > 1e100


@pytest.mark.parametrize(
    "c, needle",
    [
        ("iii", "c: has 3 entries but n has 4 media"),
        (["i", "c", "i", "i", "i"], "c: has 5 entries"),
        (["i", "x", "c", "i"], "c[1]: must be 'c' (coherent) or 'i' (incoherent), got 'x'"),
        (["i", "C", "c", "i"], "c[1]: must be 'c'"),
        (["c", "i", "c", "i"], "c[0]: the ambient is an incoherent half-space: must be 'i'"),
        (["i", "i", "c", "c"], "c[3]: the substrate is an incoherent half-space: must be 'i'"),
    ],
)
def test_bad_coherence_lists(c, needle):
    n = np.array([1.0, 1.5, 1.38, 1.0], dtype=complex)
    with pytest.raises(ValueError) as e:
        irid.incoherent(n, [np.inf, 1e6, 100.0, np.inf], c, [0.0], [550.0])
    assert needle in str(e.value) and "\n" not in str(e.value)


@pytest.mark.parametrize(
    "kwargs, error, needle",
    [
        ({"layers": [(1.5, 1e6, "no")]}, TypeError, "layers[1].coherent: must be True or False"),
        ({"layers": [{"n": 1.5, "thickness_nm": 1e6, "coherent": "no"}]}, ValueError, "layers[1]"),
        ({"ambient": {"n": 1.0, "coherent": False}}, ValueError, "ambient.coherent: not allowed"),
        ({"substrate": {"n": 1.5, "coherent": True}}, ValueError, "substrate.coherent: not allowed"),
    ],
)
def test_bad_coherence_flags_on_stacks(kwargs, error, needle):
    with pytest.raises(error) as e:
        irid.Stack(**kwargs)
    assert needle in str(e.value) and "\n" not in str(e.value)


def example_calls():
    """The calls of tmm-faster's examples/example.py (its repository's
    examples folder; the PyPI sdist does not ship it), with the same
    arguments, for when the script itself cannot be found."""
    import tmm_faster as shim

    wavelengths = np.linspace(200, 1200, 1000)
    d = [np.inf, 5, 500, 5e4, 200, np.inf]
    c = ["i", "c", "c", "i", "c", "i"]
    angles = np.linspace(0, 90, 1000)
    n_list = [1.0, 0.05 + 3.0j, 2.4 + 0.001j, 1.5, 2.4 + 0.001j, 1.0]
    n_array = np.array([n_list for _ in wavelengths])
    res_incoherent = shim.calc_incoherent(n_array, d, c, angles, wavelengths)
    res_coherent = shim.calc_coherent(n_array, d, angles, wavelengths)
    for res in (res_coherent, res_incoherent):
        plot = res["R_s"].T  # what the script gives imshow
        assert plot.shape == (len(angles), len(wavelengths)) and np.all(np.isfinite(plot))


class FakePyplot(types.ModuleType):
    """Enough of matplotlib.pyplot for the example's figure, checking what it
    is given: imshow gets finite (angles, wavelengths) arrays."""

    def __init__(self):
        super().__init__("matplotlib.pyplot")
        self.images = []

    def subplots(self, *args, **kwargs):
        plot = self

        class Axes:
            def imshow(self, data, **kw):
                plot.images.append(np.asarray(data))
                return object()

            def __getattr__(self, name):
                return lambda *a, **k: None

        class Figure:
            def colorbar(self, *a, **k):
                return None

            def savefig(self, *a, **k):
                return None

        return Figure(), [Axes(), Axes()]

    def show(self):
        return None


def test_tmm_fasters_example_runs_with_irid_in_its_place(monkeypatch, tmp_path):
    """tmm-faster's examples/example.py end to end, `import tmm_faster`
    answered by a shim over irid: the script itself when TMM_FASTER_EXAMPLE
    names it (with a stand-in for matplotlib), its calls otherwise. Its
    incoherent result must be Byrnes' inc_tmm's (and tmm-faster's, which is
    right on this stack) at sampled points."""
    shim = types.ModuleType("tmm_faster")
    shim.calc_incoherent = irid.incoherent
    shim.calc_coherent = irid.coherent
    monkeypatch.setitem(sys.modules, "tmm_faster", shim)
    script = os.environ.get("TMM_FASTER_EXAMPLE")
    if script:
        pyplot = FakePyplot()
        matplotlib = types.ModuleType("matplotlib")
        matplotlib.pyplot = pyplot
        monkeypatch.setitem(sys.modules, "matplotlib", matplotlib)
        monkeypatch.setitem(sys.modules, "matplotlib.pyplot", pyplot)
        monkeypatch.chdir(tmp_path)
        namespace = runpy.run_path(script, run_name="__main__")
        assert len(pyplot.images) == 2
        assert all(im.shape == (1000, 1000) and np.all(np.isfinite(im)) for im in pyplot.images)
        got = namespace["res_incoherent"]
    else:
        example_calls()
        wavelengths, angles = np.linspace(200, 1200, 1000), np.linspace(0, 90, 1000)
        n_list = [1.0, 0.05 + 3.0j, 2.4 + 0.001j, 1.5, 2.4 + 0.001j, 1.0]
        d, c = [np.inf, 5, 500, 5e4, 200, np.inf], ["i", "c", "c", "i", "c", "i"]
        got = shim.calc_incoherent(np.array([n_list] * 1000), d, c, angles, wavelengths)
    wi, ai = np.arange(0, 1000, 111), np.arange(0, 999, 97)
    n = np.tile(np.array([1.0, 0.05 + 3.0j, 2.4 + 0.001j, 1.5, 2.4 + 0.001j, 1.0]), (len(wi), 1))
    ref = byrnes(n, [np.inf, 5, 500, 5e4, 200, np.inf], "iccici", np.linspace(0, 90, 1000)[ai],
                 np.linspace(200, 1200, 1000)[wi])
    assert max(float(np.max(np.abs(got[k][np.ix_(wi, ai)] - ref[k]))) for k in KEYS) <= TOL
    # At exactly 90 degrees no power enters.
    assert np.all(got["R_avg"][:, -1] == 1.0) and np.all(got["T_avg"][:, -1] == 0.0)
