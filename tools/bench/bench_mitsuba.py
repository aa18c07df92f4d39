"""irid_film in Mitsuba 3: the picture of docs/mitsuba.md, and its speed
against Mitsuba's C++ `conductor` on the same scene, measured in one run.

    .venv-mitsuba/bin/python tools/bench/bench_mitsuba.py --picture docs/images/mitsuba.png

(tools/ci/mitsuba.sh makes .venv-mitsuba.) The speed scene is a unit sphere
of titanium dioxide on copper (bare copper for `conductor`) under the
constant emitter, orthographic, SIZE² pixels, SPP samples per pixel, path
tracer of depth 4, in llvm_ad_spectral. Each configuration renders once to
compile its kernels, then REPEATS times; the median of those is reported.
"""

import argparse
import statistics
import tempfile
import time
from pathlib import Path

import drjit as dr
import mitsuba as mi
import numpy as np

mi.set_variant("llvm_ad_spectral")

import irid  # noqa: E402
import irid.mitsuba  # noqa: E402

FILM = irid.Stack(ambient=1.0, layers=[("TiO2", 300.0)], substrate="copper")
COATED_GLASS = irid.Stack(ambient=1.0, layers=[("MgF2", 250.0)], substrate=1.52)


def symbolic(on):
    dr.set_flag(dr.JitFlag.SymbolicLoops, on)
    dr.set_flag(dr.JitFlag.SymbolicCalls, on)


def sphere_scene(bsdf, size):
    return mi.load_dict(
        {
            "type": "scene",
            "integrator": {"type": "path", "max_depth": 4},
            "emitter": {"type": "constant"},
            "sensor": {
                "type": "orthographic",
                "to_world": mi.ScalarTransform4f().look_at(origin=[0, 0, 4], target=[0, 0, 0], up=[0, 1, 0]),
                "film": {"type": "hdrfilm", "width": size, "height": size, "rfilter": {"type": "box"}},
            },
            "sphere": {"type": "sphere", "bsdf": bsdf},
        }
    )


def render_seconds(scene, spp, seed):
    """Wall time of one render to finished pixels (Dr.Jit's LLVM backend
    launches asynchronously: dr.eval alone may return before the work ends)."""
    start = time.perf_counter()
    image = mi.render(scene, spp=spp, seed=seed)
    dr.eval(image)
    dr.sync_thread()
    return time.perf_counter() - start


def timed_renders(scene, spp, repeats):
    first = render_seconds(scene, spp, 0)
    return first, statistics.median(render_seconds(scene, spp, seed) for seed in range(1, repeats + 1))


def speed(size, spp, repeats, table_path):
    start = time.perf_counter()
    lut = irid.bake(
        FILM,
        thickness_nm=(250.0, 350.0),
        kind="spectral",
        wavelengths_nm=(360.0, 830.0),
        resolution=(21, 64, 236),
        validation_points=2000,
    )
    lut.save(table_path)
    bake = time.perf_counter() - start
    validation = lut.header["error"]["validation"]
    conductor = {"type": "conductor", "material": "Cu"}
    film = irid.mitsuba.bsdf(FILM, thickness_nm=300.0)
    film_table = irid.mitsuba.bsdf(FILM, thickness_nm=300.0, table=table_path)
    runs = [
        ("conductor (C++), symbolic", conductor, True),
        ("conductor (C++), evaluated", conductor, False),
        ("irid_film, table, symbolic", film_table, True),
        ("irid_film, table, evaluated", film_table, False),
        ("irid_film, solver, evaluated", film, False),
    ]
    rows = []
    for name, bsdf, on in runs:
        symbolic(on)
        first, median = timed_renders(sphere_scene(bsdf, size), spp, repeats)
        rows.append((name, first, median))
    base = rows[0][2]
    print(f"sphere {size}x{size}, {spp} spp, path depth 4, llvm_ad_spectral, {repeats} timed renders each")
    print(
        f"table: 21 x 64 x 236 nodes baked in {bake:.2f} s; against the solver at {validation['points']} points: "
        f"max abs {max(validation['max_abs']):.1e} (at cos θ {validation['worst_point'][1]:.3f}), "
        f"reflected colour ΔE00 mean {validation['mean_de2000'][0]:.2f}"
    )
    print("| BSDF | first render (compiles) | median render | vs conductor |")
    print("|---|---:|---:|---:|")
    for name, first, median in rows:
        print(f"| {name} | {first:.2f} s | {median:.3f} s | {median / base:.1f}x |")


def thickness_map(width=256, height=128):
    """A smooth pattern of thickness 100-350 nm (bitmap values are nm)."""
    u, v = np.meshgrid(np.linspace(0, 1, width), np.linspace(0, 1, height))
    pattern = np.sin(9.0 * u + 2.0 * np.sin(7.0 * v)) * np.cos(5.0 * v - 3.0 * u) + 0.4 * np.sin(23.0 * u * v)
    pattern = (pattern - pattern.min()) / (pattern.max() - pattern.min())
    return mi.Bitmap((100.0 + 250.0 * pattern)[..., None].astype(np.float32))


def picture(path, spp):
    symbolic(False)
    painted = {"type": "bitmap", "bitmap": thickness_map(), "raw": True}
    floor = {"type": "diffuse", "reflectance": {"type": "checkerboard", "to_uv": mi.ScalarTransform4f().scale(8)}}
    scene = mi.load_dict(
        {
            "type": "scene",
            "integrator": {"type": "path", "max_depth": 12},
            "emitter": {"type": "constant"},
            "sensor": {
                "type": "perspective",
                "fov": 50,
                "to_world": mi.ScalarTransform4f().look_at(origin=[0, 1.4, 7.2], target=[0, -0.15, 0], up=[0, 1, 0]),
                "film": {"type": "hdrfilm", "width": 480, "height": 200, "rfilter": {"type": "gaussian"}},
            },
            "smooth": {
                "type": "sphere",
                "center": [-2.2, 0, 0],
                "bsdf": irid.mitsuba.bsdf(FILM, thickness_nm=painted),
            },
            "rough": {
                "type": "sphere",
                "center": [0, 0, 0],
                "bsdf": irid.mitsuba.bsdf(FILM, thickness_nm=painted, roughness=0.3),
            },
            "glass": {
                "type": "sphere",
                "center": [2.2, 0, 0],
                "bsdf": irid.mitsuba.bsdf(COATED_GLASS, thickness_nm=250.0),
            },
            "floor": {
                "type": "rectangle",
                "to_world": mi.ScalarTransform4f().translate([0, -1, 0]).rotate([1, 0, 0], -90).scale(8),
                "bsdf": floor,
            },
        }
    )
    start = time.perf_counter()
    image = mi.render(scene, spp=spp)
    print(f"picture: 480x200, {spp} spp, {time.perf_counter() - start:.1f} s")
    mi.util.write_bitmap(str(path), image)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--size", type=int, default=256)
    parser.add_argument("--spp", type=int, default=64)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--picture", type=Path, help="also render the docs picture to this PNG")
    parser.add_argument("--picture-spp", type=int, default=128)
    args = parser.parse_args()
    irid.mitsuba.register()
    with tempfile.TemporaryDirectory() as tmp:
        speed(args.size, args.spp, args.repeats, str(Path(tmp) / "film.exr"))
    if args.picture:
        picture(args.picture, args.picture_spp)


if __name__ == "__main__":
    main()
