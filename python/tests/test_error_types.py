"""The exception type of every entry point follows one rule (docs/python.md,
"Errors"):

- TypeError: an argument of a type its parameter never takes;
- ValueError: a value or content irid refuses (out of range, NaN, unknown
  names, malformed files and text);
- OSError (FileNotFoundError, IsADirectoryError, ...): the operating system
  cannot open, read or write a file;
- MemoryError: the call would exceed the memory budget.

The table below runs each entry point on each kind of bad input."""

import math
from types import SimpleNamespace

import numpy as np
import pytest

import irid

NAN, INF = math.nan, math.inf


@pytest.fixture(scope="module")
def f(tmp_path_factory):
    """Files and objects the bad calls use."""
    d = tmp_path_factory.mktemp("errors")
    (d / "folder").mkdir()
    (d / "junk.exr").write_bytes(b"not an exr")
    (d / "bad.csv").write_text("wl,n\n0.3,abc\n")
    (d / "latin1.csv").write_bytes("wl,n # \xb5m\n0.3,1.5\n0.9,1.5\n".encode("latin-1"))
    (d / "latin1.toml").write_bytes("# \xb5m\nambient = { n = 1.0 }\nsubstrate = { n = 1.5 }\n".encode("latin-1"))
    (d / "bad.toml").write_text("ambient = { n = 1.0 \n")
    (d / "missing-table.toml").write_text('ambient = { n = 1.0 }\nsubstrate = { table = "nowhere.csv" }\n')
    (d / "folder-table.toml").write_text('ambient = { n = 1.0 }\nsubstrate = { table = "folder" }\n')
    stack = irid.Stack(layers=[(1.33, 300.0)], substrate=1.5)
    rgb = irid.bake(stack, thickness_nm=(0, 600), resolution=(8, 4), validation_points=0)
    spectral = irid.bake(stack, thickness_nm=(0, 600), resolution=(8, 4, 5), kind="spectral", validation_points=0)
    rgb.save(d / "good.exr")
    truncated = (d / "good.exr").read_bytes()
    (d / "truncated.exr").write_bytes(truncated[: len(truncated) // 2])
    return SimpleNamespace(dir=d, missing=d / "missing", stack=stack, rgb=rgb, spectral=spectral)


def coherent(**kw):
    args = dict(n=[1.0, 1.5, 1.0], d=[INF, 100.0, INF], angles=[0.0], wavelengths=[500.0])
    args.update(kw)
    return irid.coherent(**args)


def incoherent(**kw):
    args = dict(n=[1.0, 1.5, 1.0], d=[INF, 1e6, INF], c="iii", angles=[0.0], wavelengths=[500.0])
    args.update(kw)
    return irid.incoherent(**args)


def fit(f, **kw):
    args = dict(stack=f.stack, vary=[1], wavelengths_nm=[500.0, 600.0], angles_deg=[0.0], R=np.full((2, 1), 0.05))
    args.update(kw)
    return irid.fit(**args)


def bake(f, **kw):
    return irid.bake(f.stack, **{"resolution": (4, 4), "validation_points": 0, **kw})


CASES = [
    # coherent
    ("coherent n of strings", lambda f: coherent(n="glass"), ValueError),
    ("coherent n of objects", lambda f: coherent(n=object()), TypeError),
    ("coherent n None", lambda f: coherent(n=None), TypeError),
    ("coherent ragged n", lambda f: coherent(n=[[1.0, 1.5], [1.0]]), ValueError),
    ("coherent NaN angle", lambda f: coherent(angles=[NAN]), ValueError),
    ("coherent inf wavelength", lambda f: coherent(wavelengths=[INF]), ValueError),
    ("coherent NaN thickness", lambda f: coherent(d=[INF, NAN, INF]), ValueError),
    ("coherent d too short", lambda f: coherent(d=[INF, INF]), ValueError),
    ("coherent angles None", lambda f: coherent(angles=None), TypeError),
    # incoherent
    ("incoherent c a number", lambda f: incoherent(c=5), TypeError),
    ("incoherent c of numbers", lambda f: incoherent(c=["i", 1, "i"]), TypeError),
    ("incoherent c None", lambda f: incoherent(c=None), TypeError),
    ("incoherent c too short", lambda f: incoherent(c=["i", "i"]), ValueError),
    ("incoherent c other letters", lambda f: incoherent(c=["i", "x", "i"]), ValueError),
    ("incoherent coherent ambient", lambda f: incoherent(c=["c", "i", "i"]), ValueError),
    ("incoherent NaN thickness", lambda f: incoherent(d=[INF, NAN, INF]), ValueError),
    ("incoherent lasing", lambda f: incoherent(n=[1.0, 1.5 - 0.01j, 1.5], d=[INF, 1e6, INF]), ValueError),
    ("incoherent too large", lambda f: incoherent(angles=np.zeros(10**6), wavelengths=np.full(10**6, 500.0)), MemoryError),
    # Stack(...)
    ("Stack coherent flag a string", lambda f: irid.Stack(layers=[(1.5, 1e6, "no")]), TypeError),
    ("Stack flag on the ambient", lambda f: irid.Stack(ambient={"n": 1.0, "coherent": False}), ValueError),
    ("Stack object medium", lambda f: irid.Stack(substrate=object()), TypeError),
    ("Stack bool medium", lambda f: irid.Stack(substrate=True), TypeError),
    ("Stack layers not a list", lambda f: irid.Stack(layers=5), TypeError),
    ("Stack layer not a pair", lambda f: irid.Stack(layers=[1.5]), TypeError),
    ("Stack layer of one", lambda f: irid.Stack(layers=[(1.5,)]), ValueError),
    ("Stack thickness a string", lambda f: irid.Stack(layers=[(1.5, "100")]), TypeError),
    ("Stack NaN thickness", lambda f: irid.Stack(layers=[(1.5, NAN)]), ValueError),
    ("Stack unknown material", lambda f: irid.Stack(layers=[("unobtainium", 10.0)]), ValueError),
    ("Stack NaN in a dict", lambda f: irid.Stack(substrate={"n": NAN}), ValueError),
    ("Stack array in a dict", lambda f: irid.Stack(substrate={"n": np.ones(2)}), TypeError),
    ("Stack missing CSV", lambda f: irid.Stack(substrate={"table": str(f.missing)}), FileNotFoundError),
    ("Stack folder as CSV", lambda f: irid.Stack(substrate={"table": str(f.dir / "folder")}), IsADirectoryError),
    ("Stack malformed CSV", lambda f: irid.Stack(substrate={"table": str(f.dir / "bad.csv")}), ValueError),
    ("Stack CSV not UTF-8", lambda f: irid.Stack(substrate={"table": str(f.dir / "latin1.csv")}), ValueError),
    # Stack.load / Stack.from_toml
    ("Stack.load missing", lambda f: irid.Stack.load(f.missing), FileNotFoundError),
    ("Stack.load folder", lambda f: irid.Stack.load(f.dir / "folder"), IsADirectoryError),
    ("Stack.load malformed", lambda f: irid.Stack.load(f.dir / "bad.toml"), ValueError),
    ("Stack.load not UTF-8", lambda f: irid.Stack.load(f.dir / "latin1.toml"), ValueError),
    ("Stack.load missing CSV", lambda f: irid.Stack.load(f.dir / "missing-table.toml"), FileNotFoundError),
    ("Stack.load folder as CSV", lambda f: irid.Stack.load(f.dir / "folder-table.toml"), IsADirectoryError),
    ("Stack.load a number", lambda f: irid.Stack.load(123), TypeError),
    ("Stack.from_toml malformed", lambda f: irid.Stack.from_toml("ambient = "), ValueError),
    ("Stack.from_toml missing CSV", lambda f: irid.Stack.from_toml('ambient = { n = 1.0 }\nsubstrate = { table = "x.csv" }', f.dir), FileNotFoundError),
    ("Stack.from_toml a number", lambda f: irid.Stack.from_toml(5), TypeError),
    # Stack.solve
    ("Stack.solve negative layer", lambda f: f.stack.solve([500.0], [0.0], thickness_nm=[10.0], layer=-1), ValueError),
    ("Stack.solve huge layer", lambda f: f.stack.solve([500.0], [0.0], thickness_nm=[10.0], layer=2**70), ValueError),
    ("Stack.solve layer 0", lambda f: f.stack.solve([500.0], [0.0], thickness_nm=[10.0], layer=0), ValueError),
    ("Stack.solve float layer", lambda f: f.stack.solve([500.0], [0.0], thickness_nm=[10.0], layer=1.5), TypeError),
    ("Stack.solve string layer", lambda f: f.stack.solve([500.0], [0.0], thickness_nm=[10.0], layer="1"), TypeError),
    ("Stack.solve NaN angle", lambda f: f.stack.solve([500.0], [NAN]), ValueError),
    ("Stack.solve NaN wavelength", lambda f: f.stack.solve([NAN], [0.0]), ValueError),
    ("Stack.solve inf thickness", lambda f: f.stack.solve([500.0], [0.0], thickness_nm=[INF]), ValueError),
    ("Stack.solve wavelengths of objects", lambda f: f.stack.solve(object(), [0.0]), TypeError),
    # Stack.response
    ("Stack.response NaN cos", lambda f: f.stack.response(NAN, 500.0), ValueError),
    ("Stack.response inf wavelength", lambda f: f.stack.response(0.5, INF), ValueError),
    ("Stack.response negative layer", lambda f: f.stack.response(0.5, 500.0, 10.0, layer=-1), ValueError),
    ("Stack.response float layer", lambda f: f.stack.response(0.5, 500.0, 10.0, layer=1.0), TypeError),
    ("Stack.response unknown side", lambda f: f.stack.response(0.5, 500.0, side="below"), ValueError),
    ("Stack.response side a number", lambda f: f.stack.response(0.5, 500.0, side=1), TypeError),
    ("Stack.response no broadcast", lambda f: f.stack.response(np.zeros(3), np.full(4, 500.0)), ValueError),
    ("Stack.response objects", lambda f: f.stack.response(object(), 500.0), TypeError),
    ("Stack.response too large", lambda f: f.stack.response(np.broadcast_to(0.5, (10**7, 10**7)), 500.0), MemoryError),
    # Stack.to_json / from_json
    ("Stack.to_json an argument", lambda f: f.stack.to_json(2), TypeError),
    ("Stack.from_json malformed", lambda f: irid.Stack.from_json('{"ambient": 1}'), ValueError),
    ("Stack.from_json a number", lambda f: irid.Stack.from_json(5), TypeError),
    # Stack.color
    ("fit vary 0", lambda f: fit(f, vary=[0]), ValueError),
    ("fit vary the substrate", lambda f: fit(f, vary=[2]), ValueError),
    ("fit vary a string", lambda f: fit(f, vary="a"), TypeError),
    ("fit stack a string", lambda f: irid.fit("glass", [1], [500.0, 600.0], [0.0], R=np.zeros((2, 1))), TypeError),
    ("fit NaN R", lambda f: fit(f, R=np.full((2, 1), NAN)), ValueError),
    ("fit R of the wrong shape", lambda f: fit(f, R=np.zeros((3, 1))), ValueError),
    ("fit bounds excluding the start", lambda f: fit(f, bounds=[(10.0, 20.0)]), ValueError),
    ("fit bounds of strings", lambda f: fit(f, bounds=[("a", "b")]), TypeError),
    ("fit_color unreachable target", lambda f: irid.fit_color(f.stack, [1], [0.0], [[2.0, 0.0, 0.0]]), ValueError),
    ("fit_color unknown white", lambda f: irid.fit_color(f.stack, [1], [0.0], [[0.1, 0.1, 0.1]], white="f2"), ValueError),
    ("fit_color stack None", lambda f: irid.fit_color(None, [1], [0.0], [[0.1, 0.1, 0.1]]), TypeError),
    ("Stack.color NaN angle", lambda f: f.stack.color([NAN]), ValueError),
    ("Stack.color unknown sampling", lambda f: f.stack.color([0.0], sampling="fine"), ValueError),
    ("Stack.color sampling a number", lambda f: f.stack.color([0.0], sampling=5), TypeError),
    ("Stack.color unknown white", lambda f: f.stack.color([0.0], white="f2"), ValueError),
    ("Stack.color NaN roughness", lambda f: f.stack.color([0.0], roughness=NAN), ValueError),
    ("Stack.color roughness above 1", lambda f: f.stack.color([0.0], roughness=1.01), ValueError),
    ("Stack.color negative roughness", lambda f: f.stack.color([0.0], roughness=-0.1), ValueError),
    ("Stack.color roughness a string", lambda f: f.stack.color([0.0], roughness="0.5"), TypeError),
    ("Stack.color roughness a bool", lambda f: f.stack.color([0.0], roughness=True), TypeError),
    # Material / material / index
    ("Material object", lambda f: irid.Material(object()), TypeError),
    ("Material two forms", lambda f: irid.Material(n=1.5, material="gold"), ValueError),
    ("Material missing CSV", lambda f: irid.Material(table=str(f.missing)), FileNotFoundError),
    ("material unknown", lambda f: irid.material("kryptonite"), ValueError),
    ("material a number", lambda f: irid.material(5), TypeError),
    ("Material.index NaN", lambda f: irid.material("gold").index(NAN), ValueError),
    ("Material.index NaN of a constant", lambda f: irid.Material(1.5).index([500.0, NAN]), ValueError),
    ("Material.index negative of a constant", lambda f: irid.Material(1.5).index(-500.0), ValueError),
    ("Material.index out of range", lambda f: irid.material("gold").index(20000.0), ValueError),
    ("Material.index strings", lambda f: irid.material("gold").index("red"), ValueError),
    # bake
    ("bake not a stack", lambda f: irid.bake("film"), TypeError),
    ("bake negative layer", lambda f: bake(f, layer=-1), ValueError),
    ("bake huge layer", lambda f: bake(f, layer=2**64), ValueError),
    ("bake negative resolution", lambda f: bake(f, resolution=(-1, 4)), ValueError),
    ("bake huge resolution", lambda f: bake(f, resolution=(2**70, 4)), ValueError),
    ("bake float resolution", lambda f: bake(f, resolution=(4.5, 4)), TypeError),
    ("bake resolution a string", lambda f: bake(f, resolution="44"), TypeError),
    ("bake resolution of one", lambda f: bake(f, resolution=(4,)), ValueError),
    ("bake rgb with three counts", lambda f: bake(f, resolution=(4, 4, 4)), ValueError),
    ("bake spectral with two counts", lambda f: bake(f, resolution=(4, 4), kind="spectral"), ValueError),
    ("bake rgb with wavelengths", lambda f: bake(f, wavelengths_nm=(400, 700)), ValueError),
    ("bake negative validation points", lambda f: bake(f, validation_points=-1), ValueError),
    ("bake NaN max error", lambda f: irid.bake(f.stack, max_error=NAN), ValueError),
    ("bake NaN thickness", lambda f: bake(f, thickness_nm=(NAN, 100.0)), ValueError),
    ("bake NaN cos", lambda f: bake(f, cos_theta=(0.5, NAN)), ValueError),
    ("bake unknown kind", lambda f: bake(f, kind="hyperspectral"), ValueError),
    ("bake kind a number", lambda f: bake(f, kind=5), TypeError),
    ("bake too large", lambda f: bake(f, resolution=(65536, 1024)), MemoryError),
    # Lut: made by bake and load only
    ("Lut constructor", lambda f: irid.Lut(), TypeError),
    # Lut.save (Lut.load and RoughLut.load: loader_cases below)
    ("Lut.save no folder", lambda f: f.rgb.save(f.dir / "no-such" / "t.exr"), FileNotFoundError),
    ("Lut.save onto a folder", lambda f: f.rgb.save(f.dir / "folder"), IsADirectoryError),
    # Lut.sample / validate
    ("Lut.sample NaN thickness", lambda f: f.rgb.sample([100.0, NAN], 1.0), ValueError),
    ("Lut.sample NaN cos", lambda f: f.rgb.sample(100.0, NAN), ValueError),
    ("Lut.sample spectral NaN wavelength", lambda f: f.spectral.sample(100.0, 1.0, NAN), ValueError),
    ("Lut.sample objects", lambda f: f.rgb.sample(object(), 1.0), TypeError),
    ("Lut.sample None", lambda f: f.rgb.sample(None, 1.0), TypeError),
    ("Lut.sample no broadcast", lambda f: f.rgb.sample(np.zeros(3), np.zeros(4)), ValueError),
    ("Lut.sample rgb with wavelength", lambda f: f.rgb.sample(100.0, 1.0, 500.0), ValueError),
    ("Lut.sample spectral without", lambda f: f.spectral.sample(100.0, 1.0), ValueError),
    ("Lut.validate zero points", lambda f: f.rgb.validate(0), ValueError),
    ("Lut.validate negative points", lambda f: f.rgb.validate(-5), ValueError),
    ("Lut.validate negative seed", lambda f: f.rgb.validate(10, seed=-1), ValueError),
    ("Lut.validate huge seed", lambda f: f.rgb.validate(10, seed=2**64), ValueError),
    ("Lut.validate float points", lambda f: f.rgb.validate(10.0), TypeError),
]


def loader_cases(name):
    """The file errors every table loader (irid.Lut, irid.RoughLut) raises."""
    load = getattr(irid, name).load
    return [
        (f"{name}.load missing", lambda f: load(f.missing), FileNotFoundError),
        (f"{name}.load folder", lambda f: load(f.dir / "folder"), IsADirectoryError),
        (f"{name}.load junk", lambda f: load(f.dir / "junk.exr"), ValueError),
        (f"{name}.load truncated", lambda f: load(f.dir / "truncated.exr"), ValueError),
        (f"{name}.load a number", lambda f: load(5), TypeError),
    ]


CASES += loader_cases("Lut") + loader_cases("RoughLut") + [
    ("RoughLut constructor", lambda f: irid.RoughLut(), TypeError),
    # RoughLut.sample's ValueErrors need a baked rough table: test_rough_lut.py
    ("RoughLut.sample without a table", lambda f: irid.RoughLut.sample(None, 1.0, 1.0, 0.5), TypeError),
]


@pytest.mark.parametrize("name, call, expected", CASES, ids=[c[0] for c in CASES])
def test_error_type(f, name, call, expected):
    with pytest.raises(Exception) as e:
        call(f)
    # The documented type exactly (a subclass of OSError where one is named),
    # never a neighbour such as OverflowError or a bare Exception.
    assert type(e.value) is expected, f"{name}: {type(e.value).__name__}: {e.value}"
    message = str(e.value)
    assert message and "\n" not in message, message


def public_entry_points():
    """irid's functions, and the methods of its classes, that take arguments."""
    for name in irid.__all__:
        obj = getattr(irid, name)
        if isinstance(obj, type):
            yield name  # the constructor
            for attr, member in vars(obj).items():
                if not attr.startswith("_") and callable(getattr(obj, attr)):
                    yield f"{name}.{attr}"
        elif callable(obj) and name != "materials":  # materials() takes nothing
            yield name


def test_the_table_covers_every_entry_point():
    # A new function or method fails here until its bad inputs are listed.
    labels = [c[0] for c in CASES]
    missing = [e for e in public_entry_points() if not any(label.startswith(e + " ") for label in labels)]
    assert not missing, missing
