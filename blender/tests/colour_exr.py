"""Colour difference and EXR files for the Blender tests (test_blender.py,
test_rough_cycles.py, test_eevee.py).

CIEDE2000 as irid computes it, half-float EXR tables written with the
OpenEXR package rather than with Blender (so the orientation check does not
test Blender against itself), and synthetic exports whose texels hold their
own chart coordinates.
"""

import json

import numpy as np
import OpenEXR

# ---------------------------------------------------------------- colour

# Linear sRGB (IEC 61966-2-1 primaries, D65) to CIE XYZ; (1, 1, 1) is the
# reference white of Lab, as in irid's own delta_e2000_rgb.
SRGB_TO_XYZ = np.array(
    [[0.4124, 0.3576, 0.1805], [0.2126, 0.7152, 0.0722], [0.0193, 0.1192, 0.9505]]
)


def rgb_to_lab(rgb):
    xyz = np.asarray(rgb, float) @ SRGB_TO_XYZ.T
    t = xyz / SRGB_TO_XYZ.sum(axis=1)
    d = 6.0 / 29.0
    f = np.where(t > d**3, np.cbrt(t), t / (3 * d * d) + 4.0 / 29.0)
    return np.stack(
        [116 * f[..., 1] - 16, 500 * (f[..., 0] - f[..., 1]), 200 * (f[..., 1] - f[..., 2])], -1
    )


def delta_e2000(lab1, lab2):
    """CIEDE2000 (Sharma, Wu and Dalal 2005), elementwise over the last axis."""
    L1, a1, b1 = np.moveaxis(np.asarray(lab1, float), -1, 0)
    L2, a2, b2 = np.moveaxis(np.asarray(lab2, float), -1, 0)
    c_bar = 0.5 * (np.hypot(a1, b1) + np.hypot(a2, b2))
    g = 0.5 * (1 - np.sqrt(c_bar**7 / (c_bar**7 + 25.0**7)))
    a1p, a2p = (1 + g) * a1, (1 + g) * a2
    c1p, c2p = np.hypot(a1p, b1), np.hypot(a2p, b2)
    h1p = np.degrees(np.arctan2(b1, a1p)) % 360
    h2p = np.degrees(np.arctan2(b2, a2p)) % 360
    chroma_zero = c1p * c2p == 0
    dh = h2p - h1p
    dh = np.where(dh > 180, dh - 360, np.where(dh < -180, dh + 360, dh))
    dh = np.where(chroma_zero, 0.0, dh)
    d_big_h = 2 * np.sqrt(c1p * c2p) * np.sin(np.radians(dh / 2))
    l_bar = 0.5 * (L1 + L2)
    c_bar_p = 0.5 * (c1p + c2p)
    h_sum = h1p + h2p
    h_bar = np.where(
        np.abs(h1p - h2p) > 180, np.where(h_sum < 360, h_sum + 360, h_sum - 360), h_sum
    ) / 2
    h_bar = np.where(chroma_zero, h_sum, h_bar)
    t = (
        1
        - 0.17 * np.cos(np.radians(h_bar - 30))
        + 0.24 * np.cos(np.radians(2 * h_bar))
        + 0.32 * np.cos(np.radians(3 * h_bar + 6))
        - 0.20 * np.cos(np.radians(4 * h_bar - 63))
    )
    d_theta = 30 * np.exp(-(((h_bar - 275) / 25) ** 2))
    r_c = 2 * np.sqrt(c_bar_p**7 / (c_bar_p**7 + 25.0**7))
    s_l = 1 + 0.015 * (l_bar - 50) ** 2 / np.sqrt(20 + (l_bar - 50) ** 2)
    s_c = 1 + 0.045 * c_bar_p
    s_h = 1 + 0.015 * c_bar_p * t
    r_t = -np.sin(np.radians(2 * d_theta)) * r_c
    dl, dc, dhh = (L2 - L1) / s_l, (c2p - c1p) / s_c, d_big_h / s_h
    return np.sqrt(dl**2 + dc**2 + dhh**2 + r_t * dc * dhh)


def delta_e2000_rgb(a, b):
    return delta_e2000(rgb_to_lab(a), rgb_to_lab(b))

# ---------------------------------------------------------------- files


def write_exr(path, rgba_rows):
    """An RGBA half-float EXR whose first stored row is rgba_rows[0]."""
    pixels = np.ascontiguousarray(np.asarray(rgba_rows, np.float32).astype(np.float16))
    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
    with OpenEXR.File(header, {"RGBA": pixels}) as f:
        f.write(str(path))


def read_exr_rgb(path):
    with OpenEXR.File(str(path)) as f:
        channels = f.channels()
        if "RGBA" in channels:
            return np.asarray(channels["RGBA"].pixels, float)[..., :3]
        if "RGB" in channels:
            return np.asarray(channels["RGB"].pixels, float)
        return np.stack([np.asarray(channels[c].pixels, float) for c in "RGB"], -1)


def _synthetic_chart(size_u, size_v, blue):
    """A chart's texels (gutter included): node (i, j) holds reflectance
    (i / (N_u - 1), j / (N_v - 1), blue) and transmittance (1 - the same two,
    1 - blue)."""
    i = np.arange(-1, size_u + 1).clip(0, size_u - 1) / max(size_u - 1, 1)
    j = np.arange(-1, size_v + 1).clip(0, size_v - 1) / max(size_v - 1, 1)
    x, y = np.meshgrid(i, j)  # row r = j-th angle node: row 0 is y = 0
    one = np.ones_like(x)
    return (
        np.stack([x, y, blue * one, one], -1),
        np.stack([1 - x, 1 - y, (1 - blue) * one, one], -1),
    )


def _atlas_image(charts, blue):
    """Charts stacked in one column, each inside a one-texel gutter, as a
    reflectance image whose chart k's node (i, j) holds (i / (N_u - 1),
    j / (N_v - 1), blue(k)), and their film.json entries (side, kind, rect,
    params by name). charts: dicts of a chart's params by name (side, kind,
    a, floor and the band's or corner's numbers) plus "size" (nodes along u,
    v)."""
    width = max(c["size"][0] for c in charts) + 2
    height = sum(c["size"][1] + 2 for c in charts)
    r = np.zeros((height, width, 4))
    r[..., 3] = 1.0
    entries, row = [], 0
    for k, chart in enumerate(charts):
        nu, nv = chart["size"]
        cr, _ = _synthetic_chart(nu, nv, blue(k))
        r[row:row + nv + 2, : nu + 2] = cr
        params = {key: value for key, value in chart.items() if key != "size"}
        params.update({"x0": 1, "y0": row + 1, "width": nu, "height": nv})
        entries.append({
            "side": params["side"],
            "kind": "corner" if params["kind"] == 1 else "band",
            "rect": [1, row + 1, nu, nv],
            "params": params,
        })
        row += nv + 2
    return r, entries


def _synthetic_rough(directory, rough):
    """A rough table (film.json "rough", docs/gpu.md) of `slices` slices of
    an atlas of `charts` (the front side's, as _atlas_image takes them), in
    rows of `columns`, each inside a one-texel gutter of edge copies: slice
    s's chart k holds at node (i, j) (i / (N_u - 1), j / (N_v - 1), (k + 1)
    / 16 + s / (2 (slices - 1))), so the two-slice blend at roughness r
    gives back the chart's coordinates (x, y) and (k + 1) / 16 + √r / 2.
    The atlas's thickness range is rough["thickness_nm"] (default 0-600 nm).
    Returns film.json's "rough"."""
    slices, columns = rough["slices"], rough["columns"]
    images = []
    for s in range(slices):
        image, entries = _atlas_image(rough["charts"], lambda k: (k + 1) / 16 + s / (2 * (slices - 1)))
        images.append(image)
    size_v, size_u = images[0].shape[:2]
    pitch = (size_u + 2, size_v + 2)
    rows = -(-slices // columns)
    texels = np.zeros((rows * pitch[1], columns * pitch[0], 4))
    rects = []
    for s, image in enumerate(images):
        x0, y0 = 1 + (s % columns) * pitch[0], 1 + (s // columns) * pitch[1]
        rows_ = np.arange(-1, size_v + 1).clip(0, size_v - 1)
        cols_ = np.arange(-1, size_u + 1).clip(0, size_u - 1)
        texels[y0 - 1:y0 + size_v + 1, x0 - 1:x0 + size_u + 1] = image[rows_][:, cols_]
        rects.append([x0, y0, size_u, size_v])
    write_exr(directory / "rough.exr", texels)
    thickness = list(rough.get("thickness_nm", (0.0, 600.0)))
    return {
        "texture": {"file": "rough.exr", "width": texels.shape[1], "height": texels.shape[0],
                    "format": "rgba16f", "alpha": 1.0},
        "slices": slices,
        "nodes": {"roughness": [(s / (slices - 1)) ** 2 for s in range(slices)]},
        "light_from": "ambient",
        "tiling": {
            "columns": columns,
            "slice_size": [size_u, size_v],
            "pitch": list(pitch),
            "gutter": 1,
            "slice_rects": rects,
        },
        "atlas": {"width": size_u, "height": size_v, "thickness_nm": thickness},
        "charts": entries,
    }


def _write_film(directory, reflectance, transmittance, fields):
    """Writes the two tables and a film.json of an export for the white E on
    a made-up stack (n = 1 over n = 1.5): `fields` holds what differs between
    the synthetic exports (version, domain, charts, sides, opaque, rough)."""
    height, width = reflectance.shape[:2]
    write_exr(directory / "reflectance.exr", reflectance)
    write_exr(directory / "transmittance.exr", transmittance)
    film = {
        "format": "irid-film",
        "version": fields["version"],
        "texture": {
            "width": width,
            "height": height,
            "format": "rgba16f",
            "files": {"reflectance": "reflectance.exr", "transmittance": "transmittance.exr"},
            "png": None,
            # Row order is the module's to know (it samples at 1 - v); the
            # reader rule asks only that the check is there.
            "row_check": {"reflectance": None, "transmittance": None},
        },
        "domain": fields["domain"],
        "charts": fields["charts"],
        "sides": fields["sides"],
        "white": "e",
        "stack": {
            "ambient": {"name": "n=1", "dispersion": {"constant": {"n": 1.0, "k": 0.0}}},
            "layers": [],
            "substrate": {"name": "n=1.5", "dispersion": {"constant": {"n": 1.5, "k": 0.0}}},
        },
        "layer": 1,
        "sampling": "exact",
        "opaque": fields["opaque"],
        "rough": fields["rough"],
    }
    (directory / "film.json").write_text(json.dumps(film, indent=1))


def write_synthetic_atlas(directory, charts, sides, thickness_range, opaque, rough=None):
    """A film.json version 3 export (an atlas of band and corner charts,
    docs/gpu.md) for the mapping test. charts: dicts of a chart's params by
    name (film.json charts[k].params: side, kind, a, floor and the band's or
    corner's numbers) plus "size" (nodes along u, v); they are stacked in
    one column, each inside a one-texel gutter. Chart k's node (i, j) holds
    reflectance (i / (N_u - 1), j / (N_v - 1), (k + 1) / 16) and
    transmittance (1 - the same), so a render names the chart and the point
    in it. sides: {"front": [chart numbers], "back": [...] or None}. rough,
    a dict (slices, columns, charts), adds a rough table whose slices hold
    their own coordinates (_synthetic_rough)."""
    directory.mkdir(parents=True, exist_ok=True)
    r, entries = _atlas_image(charts, lambda k: (k + 1) / 16)
    t = 1.0 - r
    t[..., 3] = 1.0
    side = lambda k, numbers: None if numbers is None else {"index": k, "charts": numbers}  # noqa: E731
    _write_film(directory, r, t, {
        "version": 3,
        "domain": {"thickness_nm": list(thickness_range), "cos_theta": [0.0, 1.0]},
        "charts": entries,
        "sides": {"front": side(0, sides["front"]), "back": side(1, sides.get("back"))},
        "opaque": opaque,
        "rough": _synthetic_rough(directory, rough) if rough else None,
    })


def write_linear_band(directory, size=(9, 7), thickness_range=(100.0, 900.0), opaque=False):
    """A version 3 export of one band chart over the whole domain with
    uniform axes (a = 0, p0 = 0, offset < 0): node (i, j) at thickness
    min + i / (N_u - 1) of the range and cos θ j / (N_v - 1), so a render of
    its Reflectance is (x, y) = (the thickness fraction, cos θ)."""
    low, high = thickness_range
    band = {"side": 0, "kind": 0, "a": 0.0, "floor": 1.0, "p0_nm": 0.0, "p_lo_nm": low,
            "p_hi_nm": high, "cos_lo": 0.0, "cos_hi": 1.0, "anchor": 0.0, "offset": -1.0,
            "size": size}
    write_synthetic_atlas(directory, [band], {"front": [0], "back": None}, thickness_range, opaque)
