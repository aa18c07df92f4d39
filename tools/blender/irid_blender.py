"""irid thin films in Blender: a Cycles/EEVEE material built from an `irid export`.

`irid export --white e` writes a directory with reflectance.exr,
transmittance.exr and film.json: an atlas of the film's exact reflected and
transmitted colour in charts over (thickness, cos θ), for light arriving
from the ambient and for light arriving from a lossless substrate, and the
closed-form mapping from (thickness, cos θ) to texture coordinates
(docs/gpu.md; film.json version 3: several charts per side in optical
thickness, chosen per lookup; version 2: one chart per side). This module
turns such a directory into a shader node group that evaluates the same
mapping and choice with math nodes (on a back face, the substrate side's
charts), samples both tables bilinearly, and shades with
a GGX Glossy BSDF coloured by the film's reflectance (no Fresnel of its own:
the table already holds it) plus, when light leaves through the substrate, a
Refraction BSDF coloured by its transmittance (into a metal the transmitted
power is absorbed). add_film_layer puts the film over a Principled BSDF.

Use it as a module from Blender's Python:

    import bpy
    import irid_blender
    mat = irid_blender.make_material("/path/to/export", thickness_nm=350.0)
    bpy.context.object.data.materials.append(mat)

or install this file as an add-on (Preferences > Add-ons > Install from Disk):
File > Import > irid film (film.json) builds the material and assigns it to
the selected objects.

What is exact: at roughness 0 the colour of every reflected and transmitted
ray is the table's bilinear interpolation of the exact film response at the
ray's angle to the shading normal. At roughness > 0 the reflection lobe's
colour is the film's reflectance pre-integrated over the GGX lobe, F_eff of
docs/rough.md, from the export's rough table (`irid export --rough`: slices
over roughness, each an atlas of the front side's charts read by the same
lookup as the smooth atlas; without it the material has no roughness:
asking for one raises ExportError); the
refraction lobe keeps the transmittance at the view angle, and a back face
seen from a substrate with its own chart the smooth reflectance at the view
angle (the rough table holds light from the ambient only).
"""

import json
import math
import os

import bpy

bl_info = {
    "name": "irid thin film",
    "author": "irid",
    "version": (0, 1, 0),
    "blender": (4, 2, 0),
    "location": "File > Import > irid film (film.json)",
    "description": "Exact thin-film iridescence from an irid export (lookup tables + node group)",
    "category": "Material",
}

FILM_FORMAT = "irid-film"
# Version 2: one chart per side in physical thickness (Chart); version 3: an
# atlas of charts in optical thickness, several per side, chosen per lookup
# (AtlasChart). Both are read.
FILM_VERSIONS = (2, 3)
# Wavelength at which a transmitting film's refraction index is taken: the
# one irid grades the substrate's critical angle at (docs/lut-format.md).
IOR_WAVELENGTH_NM = 550.0
TABLES = ("reflectance", "transmittance")
# The white Blender Cycles renders in: a flat spectrum is (1, 1, 1)
# (docs/color.md); `irid export --white e` makes that export.
BLENDER_WHITE = "e"


class ExportError(ValueError):
    """An export directory that cannot be turned into a material."""


class Chart:
    """One chart of a version 2 export (docs/gpu.md, "The mapping"): the
    thickness and cos θ domain, the warps of both axes, and the rectangle of
    texels its nodes fill."""

    def __init__(self, chart, where, atlas_size):
        params = _object(chart, "params", where)
        number = lambda key: _number(params, key, f"{where}.params")  # noqa: E731
        self.thickness_min_nm = number("thickness_min_nm")
        self.thickness_max_nm = number("thickness_max_nm")
        self.cos_min = number("cos_min")
        self.cos_max = number("cos_max")
        self.cos_crit = number("cos_crit")
        self.y_crit = number("y_crit")
        self.thickness_power = number("thickness_power")
        if self.thickness_power not in (1.0, 2.0):
            raise ExportError(
                f"irid export {where}.params.thickness_power = {self.thickness_power}, "
                "expected 1 or 2"
            )
        if not 0.0 <= self.thickness_min_nm <= self.thickness_max_nm:
            raise ExportError(
                f"irid export {where}: thickness range [{self.thickness_min_nm}, "
                f"{self.thickness_max_nm}] nm is empty or negative"
            )
        if not 0.0 <= self.cos_min <= self.cos_max <= 1.0:
            raise ExportError(
                f"irid export {where}: cos θ range [{self.cos_min}, {self.cos_max}] is not "
                "a range inside [0, 1]"
            )
        # cos_crit < 0: angle nodes uniform in cos θ; otherwise they crowd towards
        # cos_crit, a critical angle inside the range or cos_min (grazing).
        if self.cos_crit >= 0.0:
            if not self.cos_min <= self.cos_crit < self.cos_max or not 0.0 <= self.y_crit < 1.0:
                raise ExportError(
                    f"irid export {where}: angle warp centre cos {self.cos_crit} (y {self.y_crit}) "
                    f"is not inside the cos θ range [{self.cos_min}, {self.cos_max})"
                )
        self.rect = _rect([number(key) for key in ("x0", "y0", "width", "height")], where, atlas_size)


class AtlasChart:
    """One chart of a version 3 atlas (docs/gpu.md, "The mapping";
    src/atlas/chart.rs): a band of cos θ in optical thickness
    p = d · s(cos θ), s(c) = √max(1 − a (1 − c²), floor²), on a log (or
    uniform) p axis and a cos θ axis warped about an anchor (log, square
    root or uniform), or the polar corner of a free-standing film near zero
    thickness at grazing incidence. Its numbers are the uniform array's f32
    values, by name (film.json charts[k].params)."""

    BAND = ("p0_nm", "p_lo_nm", "p_hi_nm", "cos_lo", "cos_hi", "anchor", "offset")
    CORNER = ("scale_nm", "radius")

    def __init__(self, chart, where, atlas_size):
        params = _object(chart, "params", where)
        number = lambda key: _number(params, key, f"{where}.params")  # noqa: E731
        self.kind = chart.get("kind")
        if self.kind not in ("band", "corner"):
            raise ExportError(f"irid export {where}.kind: {self.kind!r}, expected 'band' or 'corner'")
        if number("kind") != (0.0 if self.kind == "band" else 1.0):
            raise ExportError(f"irid export {where}: params.kind disagrees with kind {self.kind!r}")
        self.side = number("side")
        if self.side not in (0.0, 1.0):
            raise ExportError(f"irid export {where}.params.side = {self.side}, expected 0 or 1")
        self.side = int(self.side)
        self.a, self.floor = number("a"), number("floor")
        if not (self.a >= 0.0 and 0.0 < self.floor <= 1.0):
            raise ExportError(f"irid export {where}: optical a {self.a}, floor {self.floor}")
        self.rect = _rect([number(key) for key in ("x0", "y0", "width", "height")], where, atlas_size)
        for key in self.BAND if self.kind == "band" else self.CORNER:
            setattr(self, key, number(key))
        if self.kind == "band":
            if not (self.p0_nm >= 0.0 and 0.0 <= self.p_lo_nm <= self.p_hi_nm
                    and 0.0 <= self.cos_lo <= self.cos_hi <= 1.0
                    and (self.anchor <= self.cos_lo or self.anchor >= self.cos_hi)):
                raise ExportError(f"irid export {where}: band axes out of their ranges")
        elif not (self.scale_nm > 0.0 and self.radius > 0.0):
            raise ExportError(f"irid export {where}: corner scale {self.scale_nm}, radius {self.radius}")

    def p_warp(self, p):
        """The p axis's warp U(p): ln(1 + p / p₀), or p when p₀ is 0."""
        return math.log1p(max(p, 0.0) / self.p0_nm) if self.p0_nm > 0.0 else p

    def sign(self):
        return 1.0 if self.cos_lo >= self.anchor else -1.0

    def c_warp(self, c):
        """The cos θ axis's warp W(c) = σ g(|c − anchor|)."""
        t = abs(c - self.anchor)
        if self.offset > 0.0:
            g = math.log(t + self.offset)
        elif self.offset == 0.0:
            g = math.sqrt(t)
        else:
            g = t
        return self.sign() * g

    def xy(self, d, c):
        """(x, y) in [0, 1]² of thickness d nm at cos θ c, in Python: what the
        node graph computes (the reference of the tests)."""
        s = lambda c: math.sqrt(max(1.0 - self.a * (1.0 - c * c), self.floor ** 2))  # noqa: E731
        clamp = lambda v: min(max(v, 0.0), 1.0)  # noqa: E731
        if self.kind == "corner":
            pp = d * s(c) / self.scale_nm
            return clamp(math.atan2(pp, c) / (math.pi / 2)), clamp(math.hypot(pp, c) / self.radius)
        c = min(max(c, self.cos_lo), self.cos_hi)
        u0, u1 = self.p_warp(self.p_lo_nm), self.p_warp(self.p_hi_nm)
        x = clamp((self.p_warp(d * s(c)) - u0) / (u1 - u0)) if u1 > u0 else 0.0
        v0, v1 = self.c_warp(self.cos_lo), self.c_warp(self.cos_hi)
        y = clamp((self.c_warp(c) - v0) / (v1 - v0)) if v1 > v0 else 0.0
        return x, y

    def serves(self, d, c):
        """The choice rule's test (in Python): a corner serves inside its
        radius, a band up to its cos θ maximum."""
        if self.kind == "corner":
            s = math.sqrt(max(1.0 - self.a * (1.0 - c * c), self.floor ** 2))
            return math.hypot(d * s / self.scale_nm, c) < self.radius
        return c <= self.cos_hi


def atlas_chart_for(charts, d, c):
    """The chart of a side's charts that serves (d, c): the first that
    serves it, else the last band (src/atlas/mod.rs Atlas::chart_for)."""
    for chart in charts:
        if chart.serves(d, c):
            return chart
    return [chart for chart in charts if chart.kind == "band"][-1]


def _rect(rect, where, atlas_size):
    """[x0, y0, width, height] in whole texels inside the texture, or ExportError."""
    x0, y0, w, h = rect
    if (
        any(v != int(v) for v in rect)
        or min(x0, y0) < 0
        or min(w, h) < 1
        or x0 + w > atlas_size[0]
        or y0 + h > atlas_size[1]
    ):
        raise ExportError(
            f"irid export {where}: rectangle {rect} does not lie in the "
            f"{atlas_size[0]}×{atlas_size[1]} texture"
        )
    return [int(v) for v in rect]


class Rough:
    """The export's rough table (`irid export --rough`, film.json "rough";
    docs/gpu.md "Rough films"): F_eff of light from the ambient in S
    roughness slices of one texture, slice s at roughness (s / (S − 1))².
    Each slice is an image of the rough atlas, the front side's charts in
    the smooth atlas's form (AtlasChart, rectangles inside one slice),
    chosen per lookup by the same closed form; slice s lies at its own
    rectangle, in rows of `columns` a pitch apart inside a gutter."""

    def __init__(self, rough, directory, where):
        where = f"{where}: rough"
        if "layout" in rough and "tiling" not in rough:
            raise ExportError(
                f"irid export {where}: the rough table has the old layout (one mapping in "
                "physical thickness, no charts): export it again with `irid export --rough`"
            )
        texture = _object(rough, "texture", where)
        tiling = _object(rough, "tiling", where)
        atlas = _object(rough, "atlas", where)
        name = texture.get("file")
        if not isinstance(name, str) or not name or os.path.basename(name) != name:
            raise ExportError(f"irid export {where}.texture.file is not a file name")
        self.path = os.path.join(directory, name)
        if not os.path.isfile(self.path):
            raise ExportError(f"irid export {directory}: {name} is missing")
        whole = lambda v: isinstance(v, int) and not isinstance(v, bool)  # noqa: E731
        sizes = lambda v: isinstance(v, list) and len(v) == 2 and all(whole(n) and n >= 1 for n in v)  # noqa: E731
        self.size = [texture.get("width"), texture.get("height")]
        self.slice_size = [atlas.get("width"), atlas.get("height")]
        if not (sizes(self.size) and sizes(self.slice_size)):
            raise ExportError(f"irid export {where}: texture and atlas width and height must be sizes")
        self.slices = rough.get("slices")
        self.columns = tiling.get("columns")
        self.gutter = tiling.get("gutter")
        self.pitch = tiling.get("pitch")
        if not (whole(self.slices) and self.slices >= 2 and whole(self.columns)
                and self.columns >= 1 and whole(self.gutter) and self.gutter >= 0
                and sizes(self.pitch)):
            raise ExportError(
                f"irid export {where}: needs slices ≥ 2, and tiling.columns ≥ 1, a gutter and a pitch"
            )
        if tiling.get("slice_size") != self.slice_size:
            raise ExportError(
                f"irid export {where}: tiling.slice_size {tiling.get('slice_size')} is not the "
                f"atlas's size {self.slice_size}"
            )
        nodes = rough.get("nodes")
        roughness = nodes.get("roughness") if isinstance(nodes, dict) else None
        rule = [(s / (self.slices - 1)) ** 2 for s in range(self.slices)]
        if (not isinstance(roughness, list) or len(roughness) != self.slices
                or any(not isinstance(r, (int, float)) or abs(r - want) > 1e-6
                       for r, want in zip(roughness, rule))):
            raise ExportError(
                f"irid export {where}.nodes.roughness: expected slice s at roughness (s / "
                f"{self.slices - 1})², as the node graph reads it"
            )
        self.thickness_min_nm, self.thickness_max_nm = _thickness_range(
            atlas, f"{where}.atlas.thickness_nm"
        )
        charts = rough.get("charts")
        if not isinstance(charts, list) or not charts:
            raise ExportError(f"irid export {where}.charts is missing or empty")
        # The charts' rectangles lie inside one slice; a lookup adds the
        # slice's origin.
        self.charts = tuple(
            AtlasChart(c if isinstance(c, dict) else {}, f"{where}.charts[{k}]", self.slice_size)
            for k, c in enumerate(charts)
        )
        if any(chart.side != 0 for chart in self.charts):
            raise ExportError(f"irid export {where}.charts must all serve the front side")
        if not any(chart.kind == "band" for chart in self.charts):
            raise ExportError(f"irid export {where}.charts has no band chart")
        # The node graph places a slice by the closed form; the export's own
        # rectangles must agree with it.
        rects = tiling.get("slice_rects")
        if not isinstance(rects, list) or len(rects) != self.slices:
            raise ExportError(f"irid export {where}.tiling.slice_rects must list every slice")
        for s, rect in enumerate(rects):
            placed = list(self.slice_origin(s)) + list(self.slice_size)
            if not isinstance(rect, list) or rect != placed:
                raise ExportError(
                    f"irid export {where}: slice {s} lies at {rect}, not at {placed} as "
                    "the tiling's closed form puts it"
                )
            _rect(placed, f"{where}: slice {s}", self.size)

    def slice_origin(self, s):
        """The texel of slice s's corner, where its charts' rectangles
        start (docs/gpu.md)."""
        return (
            self.gutter + (s % self.columns) * self.pitch[0],
            self.gutter + (s // self.columns) * self.pitch[1],
        )


class Export:
    """A checked export directory: the texture files, the atlas's charts and
    which side reads which."""

    def __init__(self, directory):
        self.directory = os.path.abspath(os.fspath(directory))
        film_path = os.path.join(self.directory, "film.json")
        if not os.path.isdir(self.directory):
            raise ExportError(f"irid export {self.directory}: not a directory")
        if not os.path.isfile(film_path):
            raise ExportError(f"irid export {self.directory}: film.json is missing")
        try:
            with open(film_path, encoding="utf-8") as f:
                film = json.load(f)
        except (OSError, UnicodeDecodeError, json.JSONDecodeError) as e:
            raise ExportError(f"irid export {film_path}: not readable JSON ({e})") from None
        self.film = film
        where = film_path
        if not isinstance(film, dict):
            raise ExportError(f"irid export {where}: expected a JSON object")
        if film.get("format") != FILM_FORMAT:
            raise ExportError(
                f"irid export {where}: format {film.get('format')!r}, expected {FILM_FORMAT!r}"
            )
        self.version = film.get("version")
        if self.version not in FILM_VERSIONS or isinstance(self.version, bool):
            raise ExportError(
                f"irid export {where}: film.json version {film.get('version')!r}; this module "
                f"reads versions {' and '.join(map(str, FILM_VERSIONS))}: export the film again "
                "with the irid it came with"
            )
        texture = _object(film, "texture", where)
        self.size = (texture.get("width"), texture.get("height"))
        if not all(isinstance(v, int) and not isinstance(v, bool) and v >= 1 for v in self.size):
            raise ExportError(f"irid export {where}: texture.width and height must be sizes")
        charts = film.get("charts")
        if not isinstance(charts, list) or not charts:
            raise ExportError(f"irid export {where}: 'charts' is missing or empty")
        kind = Chart if self.version == 2 else AtlasChart
        self.charts = [
            kind(c if isinstance(c, dict) else {}, f"{where}: charts[{k}]", self.size)
            for k, c in enumerate(charts)
        ]
        sides = _object(film, "sides", where)
        if self.version == 2:
            # One chart per side: front and back are Chart objects.
            self.front = self.charts[self._chart_of(sides, "front", where)]
            self.back = None
            if sides.get("back") is not None:
                self.back = self.charts[self._chart_of(sides, "back", where)]
            self.thickness_min_nm = self.front.thickness_min_nm
            self.thickness_max_nm = self.front.thickness_max_nm
        else:
            # Several charts per side, in the order the choice rule reads
            # them: front and back are tuples of AtlasChart (the same tuple
            # when both sides read the same charts).
            self.front = self._charts_of(sides, "front", where)
            self.back = None
            if sides.get("back") is not None:
                self.back = self._charts_of(sides, "back", where)
                if self.back == self.front:
                    self.back = self.front
            self.thickness_min_nm, self.thickness_max_nm = _thickness_range(
                _object(film, "domain", where), f"{where}: domain.thickness_nm"
            )
        opaque = film.get("opaque")
        if not isinstance(opaque, bool):
            raise ExportError(f"irid export {where}: 'opaque' must be true or false")
        self.opaque = opaque
        files = _object(texture, "files", f"{where}: texture")
        self.paths = {}
        for table in TABLES:
            name = files.get(table)
            if not isinstance(name, str) or not name or os.path.basename(name) != name:
                raise ExportError(f"irid export {where}: texture.files.{table} is not a file name")
            path = os.path.join(self.directory, name)
            if not os.path.isfile(path):
                raise ExportError(f"irid export {self.directory}: {name} is missing")
            self.paths[table] = path
        self.white = film.get("white")
        if self.white != BLENDER_WHITE:
            raise ExportError(
                f"irid export {where}: made for white {self.white!r}, but Blender's colours "
                f"are white E (a flat spectrum is 1, 1, 1): export it again with `--white e`"
            )
        self.stack = film.get("stack")
        # The rough table (`irid export --rough`): null or absent without it.
        rough = film.get("rough")
        self.rough = None
        if rough is not None:
            if not isinstance(rough, dict):
                raise ExportError(f"irid export {where}: 'rough' is not an object")
            if rough.get("light_from") != "ambient":
                raise ExportError(
                    f"irid export {where}: rough.light_from {rough.get('light_from')!r}, "
                    "expected 'ambient'"
                )
            self.rough = Rough(rough, self.directory, where)
        self.label = os.path.basename(self.directory.rstrip(os.sep)) or "film"

    def _charts_of(self, sides, side, where):
        """Version 3: the side's charts, in the atlas's order (the order the
        choice rule reads them in), each serving that side."""
        entry = sides.get(side)
        numbers = entry.get("charts") if isinstance(entry, dict) else None
        index = 0 if side == "front" else 1
        if (not isinstance(numbers, list) or not numbers
                or not all(isinstance(k, int) and not isinstance(k, bool)
                           and 0 <= k < len(self.charts) for k in numbers)):
            raise ExportError(f"irid export {where}: sides.{side}.charts is not a list of the charts")
        charts = tuple(self.charts[k] for k in sorted(set(numbers)))
        served = {chart.side for chart in charts}
        if len(served) != 1:
            raise ExportError(f"irid export {where}: sides.{side}.charts serve sides {sorted(served)}")
        if served != {index} and not (side == "back" and served == {0}):
            raise ExportError(f"irid export {where}: sides.{side}.charts serve side {served.pop()}")
        if not any(chart.kind == "band" for chart in charts):
            raise ExportError(f"irid export {where}: sides.{side} has no band chart")
        return charts

    def _chart_of(self, sides, side, where):
        entry = sides.get(side)
        chart = entry.get("chart") if isinstance(entry, dict) else None
        if not isinstance(chart, int) or isinstance(chart, bool) or not 0 <= chart < len(self.charts):
            raise ExportError(f"irid export {where}: sides.{side}.chart is not one of the charts")
        return chart

    def thickness_fraction(self, thickness_nm):
        """The 0-1 thickness socket value of a thickness in nm (the export's range)."""
        t = float(thickness_nm)
        span = self.thickness_max_nm - self.thickness_min_nm
        tolerance = 1e-9 * max(1.0, self.thickness_max_nm)
        if not (self.thickness_min_nm - tolerance <= t <= self.thickness_max_nm + tolerance):
            raise ValueError(
                f"thickness {t} nm is outside the export's range "
                f"[{self.thickness_min_nm}, {self.thickness_max_nm}] nm"
            )
        if span == 0.0:
            return 0.0
        return min(1.0, max(0.0, (t - self.thickness_min_nm) / span))

    def rough_applies_to_back_faces(self):
        """Whether the rough table (light from the ambient) holds a back
        face's F_eff too: a back face reads the front chart (an opaque film:
        the back face of a film on metal) or the two sides are one chart (a
        free-standing film)."""
        return self.back is None or self.back is self.front

    def require_rough(self, why):
        """ExportError unless the export has the rough table."""
        if self.rough is None:
            raise ExportError(
                f"irid export {self.directory}: {why}, but the export has no rough table "
                "(film.json \"rough\" is null): export it again with `irid export --rough`"
            )

    def transmits(self):
        """Whether light leaves through the substrate: film.json's "opaque" is
        false (a lossless substrate that the film lets light into). Into an
        absorbing substrate (a metal) the transmitted power is absorbed, so no
        refraction lobe is drawn."""
        return not self.opaque

    def relative_ior(self):
        """Substrate over ambient refractive index at IOR_WAVELENGTH_NM, from the stack."""
        try:
            n_ambient = _index_at(self.stack["ambient"], IOR_WAVELENGTH_NM)
            n_substrate = _index_at(self.stack["substrate"], IOR_WAVELENGTH_NM)
        except (KeyError, TypeError, ValueError) as e:
            raise ExportError(
                f"irid export {self.directory}: the stack in film.json does not give the "
                f"substrate's index ({e}); pass ior= explicitly"
            ) from None
        return n_substrate / n_ambient


def _object(parent, key, where):
    value = parent.get(key)
    if not isinstance(value, dict):
        raise ExportError(f"irid export {where}: '{key}' is missing or not an object")
    return value


def _number(parent, key, where):
    value = parent.get(key)
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise ExportError(f"irid export {where}.{key}: expected a finite number, got {value!r}")
    return float(value)


def _thickness_range(parent, where):
    """parent["thickness_nm"], [min, max] nm with 0 ≤ min ≤ max, as floats."""
    value = parent.get("thickness_nm")
    if (not isinstance(value, list) or len(value) != 2
            or not all(isinstance(v, (int, float)) and not isinstance(v, bool)
                       and math.isfinite(v) for v in value)
            or not 0.0 <= value[0] <= value[1]):
        raise ExportError(f"irid export {where} is not a thickness range in nm")
    return float(value[0]), float(value[1])


def _index_at(material, wavelength_nm):
    """Real part of a serialized irid material's index (docs/lut-format.md, `stack`)."""
    dispersion = material["dispersion"]
    um = wavelength_nm * 1e-3
    if "constant" in dispersion:
        n = dispersion["constant"]["n"]
    elif "cauchy" in dispersion:
        c = dispersion["cauchy"]
        n = c["a"] + c["b"] / um**2 + c.get("c", 0.0) / um**4
    elif "sellmeier" in dispersion:
        s = dispersion["sellmeier"]
        n2 = s.get("a", 1.0) + sum(b * um**2 / (um**2 - c) for b, c in zip(s["b"], s["c"]))
        n = math.sqrt(n2)
    elif "table" in dispersion:
        t = dispersion["table"]
        n = _interp(wavelength_nm, t["wavelength_nm"], t["n"])
    else:
        raise ValueError(f"unknown dispersion {sorted(dispersion)}")
    if not (isinstance(n, (int, float)) and math.isfinite(n) and n > 0):
        raise ValueError(f"index {n!r} is not a positive number")
    return float(n)


def _interp(x, xs, ys):
    if not xs or len(xs) != len(ys) or not xs[0] <= x <= xs[-1]:
        raise ValueError(f"{x} nm is outside the material's table")
    for i in range(1, len(xs)):
        if x <= xs[i]:
            f = (x - xs[i - 1]) / (xs[i] - xs[i - 1])
            return ys[i - 1] + f * (ys[i] - ys[i - 1])
    return ys[-1]


class _Builder:
    """Adds nodes and links to a node tree, laid out in columns."""

    def __init__(self, tree):
        self.tree = tree

    def node(self, kind, column, row, label=None, **props):
        node = self.tree.nodes.new(kind)
        node.location = (200.0 * column, -160.0 * row)
        if label:
            node.label = label
        for key, value in props.items():
            setattr(node, key, value)
        return node

    def math(self, operation, column, row, a, b=None, c=None, label=None):
        """A Math node; each operand is an output socket or a constant."""
        node = self.node("ShaderNodeMath", column, row, label, operation=operation)
        for i, operand in enumerate((a, b, c)):
            if operand is None:
                continue
            if isinstance(operand, (int, float)):
                node.inputs[i].default_value = float(operand)
            else:
                self.link(operand, node.inputs[i])
        return node.outputs[0]

    def link(self, output, input_):
        self.tree.links.new(output, input_)


def make_node_group(export_dir, name=None, ior=None):
    """A shader node group for an export: inputs Thickness (0-1 over the export's
    thickness range), Thickness nm, Roughness (only when the export has the
    rough table) and Normal; outputs BSDF, Reflection, Reflectance and
    Transmittance (docs/blender.md). A back face is shaded with the export's
    back side (light arriving from the substrate), when it has one. Without
    the rough table both lobes are mirror-smooth: the group has no Roughness
    input, so no roughness can reach it that it would render wrongly.

    Raises ExportError for a bad export directory; nothing stays in the .blend
    when building fails."""
    export = export_dir if isinstance(export_dir, Export) else Export(export_dir)
    if not export.transmits():
        ior = None  # Glossy only: nothing leaves through the substrate
    elif ior is None:
        ior = export.relative_ior()
    group_name = name or f"irid film {export.label}"
    created = []
    try:
        images = {}
        files = [(table, export.paths[table], export.size) for table in TABLES]
        if export.rough is not None:
            files.append(("rough", export.rough.path, export.rough.size))
        for table, path, size in files:
            images[table] = _load_image(path, size, f"{group_name} {table}")
            created.append(images[table])
        group = bpy.data.node_groups.new(group_name, "ShaderNodeTree")
        created.append(group)
        _build_group(group, export, images, ior)
    except BaseException:
        for block in reversed(created):
            _remove(block)
        raise
    return group


def make_material(export_dir, thickness_nm=None, name=None, roughness=0.0, ior=None):
    """A material shading with the film of an `irid export` directory.

    thickness_nm: the film's thickness, a constant inside the export's range,
    set on the group's Thickness nm input; None leaves the 0-1 Thickness input
    (over the range, like glTF's iridescenceThicknessTexture) for an attribute
    or texture to drive (default 0.5). roughness: GGX roughness of both
    lobes, 0 to 1; above 0 the reflection lobe's colour is the film's F_eff
    from the export's rough table (`irid export --rough`), which it then
    needs; None leaves the group's Roughness input (default 0) for a texture
    or value to drive, and needs the rough table too. ior: relative index of
    refraction when the film transmits into a lossless substrate (default:
    substrate over ambient at 550 nm, from the stack in film.json); over an
    absorbing substrate (a metal) the material has no refraction lobe.

    Raises ExportError (a ValueError) with one message for a missing file, a
    damaged film.json, an export for another white than Blender's (`--white
    e`) or a roughness above 0 (or None) with an export without the rough
    table; ValueError for a thickness outside the export's range or a
    roughness outside [0, 1]; nothing half-built stays in the .blend."""
    export = Export(export_dir)
    if thickness_nm is not None:
        export.thickness_fraction(thickness_nm)  # refuses one outside the range
    if roughness is None:
        export.require_rough("roughness=None leaves the roughness to a node")
    else:
        roughness = float(roughness)
        if not 0.0 <= roughness <= 1.0:
            raise ValueError(f"roughness {roughness} is outside [0, 1]")
        if roughness > 0.0:
            export.require_rough(f"roughness {roughness:g} asks for the film's rough reflectance")
    material_name = name or f"irid {export.label}"
    group = make_node_group(export, name=f"{material_name} film", ior=ior)
    material = None
    try:
        material = bpy.data.materials.new(material_name)
        if material.node_tree is None:  # Blender before 5.0 creates it on request
            material.use_nodes = True
        tree = material.node_tree
        tree.nodes.clear()
        build = _Builder(tree)
        film = build.node("ShaderNodeGroup", 0, 0, label="irid film")
        film.node_tree = group
        film.width = 220
        out = build.node("ShaderNodeOutputMaterial", 2, 0)
        build.link(film.outputs["BSDF"], out.inputs["Surface"])
        if thickness_nm is not None:
            film.inputs["Thickness nm"].default_value = float(thickness_nm)
        if export.rough is not None:
            film.inputs["Roughness"].default_value = roughness or 0.0
        material["irid_export"] = export.directory
        if thickness_nm is not None:
            material["irid_thickness_nm"] = float(thickness_nm)
    except BaseException:
        if material is not None:
            _remove(material)
        images = [n.image for n in group.nodes if n.bl_idname == "ShaderNodeTexImage"]
        _remove(group)
        for image in set(images):
            _remove(image)
        raise
    return material


def _load_image(path, expected_size, name):
    try:
        image = bpy.data.images.load(path, check_existing=False)
    except RuntimeError as e:
        raise ExportError(f"irid export {path}: Blender cannot read it ({e})") from None
    try:
        image.name = name
        image.colorspace_settings.name = _texture_colorspace(image)
        image.alpha_mode = "CHANNEL_PACKED"
        # Reading the size loads the pixels: a damaged file shows here, not at render time.
        size = tuple(image.size)
        if size == (0, 0):
            raise ExportError(f"irid export {path}: Blender cannot read it (damaged or not an image)")
        if size != tuple(expected_size):
            raise ExportError(
                f"irid export {path}: image is {size[0]}×{size[1]}, film.json says "
                f"{expected_size[0]}×{expected_size[1]}"
            )
    except BaseException:
        _remove(image)
        raise
    return image


def _texture_colorspace(image):
    """The export's colours are linear sRGB, i.e. linear Rec.709 primaries, with
    no transfer curve. Tagged so, Blender converts them into the scene's
    working space (Blender 5.0 offers ACEScg and Rec.2020, where film colours
    outside Rec.709 keep their negative Rec.709 channels instead of being
    clipped by the BSDF); in the default Rec.709 working space it is the same
    as Non-Color. Blender builds without that colour space read them as
    Non-Color (raw numbers)."""
    names = image.colorspace_settings.bl_rna.properties["name"].enum_items.keys()
    return "Linear Rec.709" if "Linear Rec.709" in names else "Non-Color"


def _remove(block):
    collections = {
        bpy.types.Image: bpy.data.images,
        bpy.types.Material: bpy.data.materials,
        bpy.types.NodeTree: bpy.data.node_groups,
    }
    for kind, collection in collections.items():
        if isinstance(block, kind):
            collection.remove(block)
            return


def _build_group(group, export, images, ior):
    _group_interface(group.interface, export)
    build = _Builder(group)
    inputs = build.node("NodeGroupInput", 0, 0)
    outputs = build.node("NodeGroupOutput", 12, 0)
    geometry = build.node("ShaderNodeNewGeometry", 0, 4)
    x = _thickness_fraction(build, export, inputs)
    normal = _shading_normal(build, inputs, geometry)
    # cos θ: the incoming direction against the shading normal, on the side
    # the light arrives from.
    dot = build.node("ShaderNodeVectorMath", 2, 4, label="cos θ", operation="DOT_PRODUCT")
    build.link(geometry.outputs["Incoming"], dot.inputs[0])
    build.link(normal, dot.inputs[1])
    cos = build.math("ABSOLUTE", 2.5, 4, dot.outputs["Value"])
    # What an atlas's charts read: the thickness in nm, cos θ at most 1.
    span = export.thickness_max_nm - export.thickness_min_nm
    d = build.math("MULTIPLY_ADD", 2, -1, x, span, export.thickness_min_nm, label="thickness nm")
    c = build.math("MINIMUM", 3, 4, cos, 1.0, label="cos θ ≤ 1")
    if export.version == 2:
        side_uv = lambda side, row: _chart_uv(build, side, export.size, x, cos, row)  # noqa: E731
    else:
        side_uv = lambda side, row: _atlas_uv(build, side, export.size, d, c, row)  # noqa: E731
    uv = side_uv(export.front, 0)
    if export.back is not None and export.back is not export.front:
        # A back face is seen from the substrate: the back side's chart(s).
        # uv = front + backfacing · (back − front): one lookup per image.
        back = side_uv(export.back, 6 if export.version == 2 else 6 * len(export.front) + 2)
        uv = _blend(build, uv, back, geometry.outputs["Backfacing"], 7.5, 3, "uv of the side")

    colours = {}
    for row, table in enumerate(TABLES):
        tex = _image_node(build, images[table], 9, 1 + 2 * row, table)
        build.link(uv, tex.inputs["Vector"])
        colours[table] = tex.outputs["Color"]
    roughness = inputs.outputs["Roughness"] if export.rough is not None else None
    reflectance = colours["reflectance"]
    if roughness is not None:
        reflectance = _rough_reflectance(
            build, export, images["rough"], d, c, roughness, reflectance, geometry
        )
    build.link(reflectance, outputs.inputs["Reflectance"])
    build.link(colours["transmittance"], outputs.inputs["Transmittance"])

    glossy = build.node("ShaderNodeBsdfGlossy", 11.5, -1, label="film reflection", distribution="GGX")
    build.link(reflectance, glossy.inputs["Color"])
    _set_roughness(build, glossy, roughness)
    build.link(normal, glossy.inputs["Normal"])
    build.link(glossy.outputs["BSDF"], outputs.inputs["Reflection"])
    if ior is None:
        build.link(glossy.outputs["BSDF"], outputs.inputs["BSDF"])
        return
    # Cycles' Refraction BSDF takes 1 / IOR on a back face: from the
    # substrate the light refracts into the ambient, and past the critical
    # angle it does not (where the back side's transmittance is 0).
    refraction = build.node(
        "ShaderNodeBsdfRefraction", 11.5, 1, label="film transmission", distribution="GGX"
    )
    refraction.inputs["IOR"].default_value = float(ior)
    build.link(colours["transmittance"], refraction.inputs["Color"])
    _set_roughness(build, refraction, roughness)
    build.link(normal, refraction.inputs["Normal"])
    add = build.node("ShaderNodeAddShader", 12, -1)
    build.link(glossy.outputs["BSDF"], add.inputs[0])
    build.link(refraction.outputs["BSDF"], add.inputs[1])
    build.link(add.outputs["Shader"], outputs.inputs["BSDF"])


def _set_roughness(build, bsdf, roughness):
    """The lobe's GGX roughness: the group's Roughness input, or 0 (mirror)
    in a group without one."""
    if roughness is None:
        bsdf.inputs["Roughness"].default_value = 0.0
    else:
        build.link(roughness, bsdf.inputs["Roughness"])


def _image_node(build, image, column, row, label):
    """An Image Texture node sampling like the GPU: bilinear, clamp to edge."""
    tex = build.node(
        "ShaderNodeTexImage",
        column,
        row,
        label=label,
        interpolation="Linear",
        extension="EXTEND",
        projection="FLAT",
    )
    tex.image = image
    return tex


def _blend(build, a, b, weight, column, row, label):
    """a + weight · (b − a) for vector (or colour) sockets and a float socket
    weight: b where weight is 1, exactly a where it is 0."""
    step = build.node("ShaderNodeVectorMath", column, row, label="b − a", operation="SUBTRACT")
    build.link(b, step.inputs[0])
    build.link(a, step.inputs[1])
    scale = build.node("ShaderNodeVectorMath", column + 0.5, row, label="× weight", operation="SCALE")
    build.link(step.outputs["Vector"], scale.inputs[0])
    build.link(weight, scale.inputs["Scale"])
    total = build.node("ShaderNodeVectorMath", column + 1, row, label=label, operation="ADD")
    build.link(a, total.inputs[0])
    build.link(scale.outputs["Vector"], total.inputs[1])
    return total.outputs["Vector"]


def _rough_reflectance(build, export, image, d, c, roughness, smooth, geometry):
    """The reflection lobe's colour: F_eff from the rough table where the
    roughness is above 0, exactly the smooth film's reflectance (`smooth`)
    where it is 0. As irid_film_rough (shaders/irid_film_rough.wgsl): the
    rough atlas's chart lookup at thickness d nm and cos θ c (the smooth
    atlas's closed form, _atlas_uv), the slice position s = √roughness ·
    (S − 1), one bilinear lookup in each of the two slices around it (the
    chart's coordinates moved to the slice's rectangle), blended linearly.
    The table holds light from the ambient: a back face of a film with a
    distinct back side keeps the back chart's smooth reflectance at the view
    angle (docs/blender.md)."""
    rough = export.rough
    top = 14 + 6 * len(export.charts)  # below the smooth lookups' nodes
    # Blender's square root is 0 below 0; the clamp takes a roughness above 1 to 1.
    root = build.math("SQRT", 1, top, roughness, label="√roughness, clamped")
    root.node.use_clamp = True
    s = build.math("MULTIPLY", 2, top, root, float(rough.slices - 1), label="slice position")
    s0 = build.math("MINIMUM", 3, top, build.math("FLOOR", 2.5, top, s), float(rough.slices - 2),
                    label="slice below")
    weight = build.math("SUBTRACT", 3.5, top, s, s0, label="weight of the slice above")
    s1 = build.math("ADD", 3.5, top + 1, s0, 1.0, label="slice above")
    # The rough atlas's own thickness range (irid_film_rough clamps to it).
    clamp = build.node("ShaderNodeClamp", 2.5, top + 4, label="thickness in the rough atlas")
    build.link(d, clamp.inputs["Value"])
    clamp.inputs["Min"].default_value = rough.thickness_min_nm
    clamp.inputs["Max"].default_value = rough.thickness_max_nm
    uv = _atlas_uv(build, rough.charts, rough.size, clamp.outputs["Result"], c, top + 4)
    colours = []
    for k, slice_ in enumerate((s0, s1)):
        at = top + 2 + 2 * k
        moved = build.node("ShaderNodeVectorMath", 8.5, at, label="uv in the slice", operation="ADD")
        build.link(uv, moved.inputs[0])
        build.link(_slice_offset(build, rough, slice_, at), moved.inputs[1])
        tex = _image_node(build, image, 9, at, f"rough slice {'above' if k else 'below'}")
        build.link(moved.outputs["Vector"], tex.inputs["Vector"])
        colours.append(tex.outputs["Color"])
    f_eff = _blend(build, colours[0], colours[1], weight, 9.5, top + 3, "F_eff")
    use = build.math("GREATER_THAN", 9.5, top, roughness, 0.0, label="rough")
    if not export.rough_applies_to_back_faces():
        front = build.math("SUBTRACT", 9.5, top + 1, 1.0, geometry.outputs["Backfacing"])
        use = build.math("MULTIPLY", 10, top + 1, use, front, label="rough, front face")
    return _blend(build, smooth, f_eff, use, 10.5, top + 2, "reflectance of the lobe")


def _group_interface(iface, export):
    """The node group's sockets (docs/blender.md lists them)."""
    sock = iface.new_socket("Thickness", in_out="INPUT", socket_type="NodeSocketFloat")
    sock.subtype = "FACTOR"
    sock.min_value, sock.max_value, sock.default_value = 0.0, 1.0, 0.5
    sock.description = (
        f"Film thickness: 0 = {export.thickness_min_nm:g} nm, 1 = {export.thickness_max_nm:g} nm "
        "(used while Thickness nm is below 0)"
    )
    sock = iface.new_socket("Thickness nm", in_out="INPUT", socket_type="NodeSocketFloat")
    sock.min_value, sock.max_value, sock.default_value = -1.0, 1.0e6, -1.0
    sock.description = (
        f"Film thickness in nm, clamped to {export.thickness_min_nm:g}-"
        f"{export.thickness_max_nm:g} nm; below 0 (the default), the 0-1 Thickness input is used"
    )
    if export.rough is not None:
        sock = iface.new_socket("Roughness", in_out="INPUT", socket_type="NodeSocketFloat")
        sock.subtype = "FACTOR"
        sock.min_value, sock.max_value, sock.default_value = 0.0, 1.0, 0.0
        sock.description = (
            "GGX roughness of both lobes; above 0 the reflection's colour is the film's "
            "F_eff from the export's rough table"
        )
    sock = iface.new_socket("Normal", in_out="INPUT", socket_type="NodeSocketVector")
    sock.hide_value = True
    sock.description = (
        "Shading normal of the film's angle and of both lobes (a normal map, a "
        "Principled coat's normal); unlinked, the surface's own"
    )
    iface.new_socket("BSDF", in_out="OUTPUT", socket_type="NodeSocketShader")
    sock = iface.new_socket("Reflection", in_out="OUTPUT", socket_type="NodeSocketShader")
    sock.description = "The reflection lobe alone, for layering over another shader"
    for table in ("Reflectance", "Transmittance"):
        iface.new_socket(table, in_out="OUTPUT", socket_type="NodeSocketColor")


def _thickness_fraction(build, export, inputs):
    """The thickness as a fraction of the export's range, clamped: from
    Thickness nm when it is 0 or more, else the 0-1 Thickness input."""
    span = export.thickness_max_nm - export.thickness_min_nm
    scale = 1.0 / span if span > 0.0 else 0.0
    nm = inputs.outputs["Thickness nm"]
    from_nm = build.math("MULTIPLY_ADD", 0.5, -1, nm, scale, -export.thickness_min_nm * scale)
    use_nm = build.math("GREATER_THAN", 0.5, -2, nm, -0.5, label="Thickness nm given")
    towards = build.math("SUBTRACT", 1, -1, from_nm, inputs.outputs["Thickness"])
    x = build.math(
        "MULTIPLY_ADD", 1.5, -1, use_nm, towards, inputs.outputs["Thickness"], label="x = clamp(thickness)"
    )
    x.node.use_clamp = True
    return x


def _shading_normal(build, inputs, geometry):
    """The Normal input, normalized, when it is linked (not zero); else the
    surface's shading normal."""
    given = inputs.outputs["Normal"]
    length = build.node("ShaderNodeVectorMath", 0.5, 6, operation="LENGTH")
    build.link(given, length.inputs[0])
    linked = build.math("GREATER_THAN", 1, 6, length.outputs["Value"], 1e-6, label="Normal linked")
    unit = build.node("ShaderNodeVectorMath", 0.5, 7, operation="NORMALIZE")
    build.link(given, unit.inputs[0])
    step = build.node("ShaderNodeVectorMath", 1, 7, operation="SUBTRACT")
    build.link(unit.outputs["Vector"], step.inputs[0])
    build.link(geometry.outputs["Normal"], step.inputs[1])
    scale = build.node("ShaderNodeVectorMath", 1.5, 7, operation="SCALE")
    build.link(step.outputs["Vector"], scale.inputs[0])
    build.link(linked, scale.inputs["Scale"])
    normal = build.node("ShaderNodeVectorMath", 2, 6, label="shading normal", operation="ADD")
    build.link(geometry.outputs["Normal"], normal.inputs[0])
    build.link(scale.outputs["Vector"], normal.inputs[1])
    return normal.outputs["Vector"]


def _mapping_xy(build, mapping, x, cos, row):
    """Where (thickness fraction x, cos θ) lies in a rectangle of nodes with
    this mapping, (x, y) in [0, 1]² (docs/gpu.md, "The mapping"), in math
    nodes with the mapping's numbers written into them."""
    # x: square-rooted when the thickness nodes crowd towards the minimum
    # (thickness power 2).
    if mapping.thickness_power == 2.0:
        x = build.math("SQRT", 1.5, row, x, label="x = sqrt(x)")
    clamp = build.node("ShaderNodeClamp", 3, row + 2, label="clamp to the chart")
    build.link(cos, clamp.inputs["Value"])
    clamp.inputs["Min"].default_value = mapping.cos_min
    clamp.inputs["Max"].default_value = mapping.cos_max
    c = clamp.outputs["Result"]

    # y: the angle warp, linear in cos θ or square-root on each side of
    # cos_crit (a branch-free form: one of the two roots is zero; with
    # cos_crit = cos_min there is no side below).
    if mapping.cos_max == mapping.cos_min:
        y = build.math("MULTIPLY", 4, row + 2, c, 0.0, label="y = 0 (one angle)")
    elif mapping.cos_crit < 0.0:
        span = mapping.cos_max - mapping.cos_min
        y = build.math("MULTIPLY_ADD", 4, row + 2, c, 1.0 / span, -mapping.cos_min / span, label="y")
    else:
        cc, yc = mapping.cos_crit, mapping.y_crit
        above = build.math(
            "MULTIPLY_ADD", 4, row + 2, c, 1.0 / (mapping.cos_max - cc), -cc / (mapping.cos_max - cc)
        )
        above = build.math("SQRT", 5, row + 2, build.math("MAXIMUM", 4.5, row + 2, above, 0.0))
        y = build.math("MULTIPLY_ADD", 5.5, row + 2, above, 1.0 - yc, yc, label="y")
        if cc > mapping.cos_min:
            below = build.math(
                "MULTIPLY_ADD", 4, row + 3, c, -1.0 / (cc - mapping.cos_min), cc / (cc - mapping.cos_min)
            )
            below = build.math("SQRT", 5, row + 3, build.math("MAXIMUM", 4.5, row + 3, below, 0.0))
            y = build.math("MULTIPLY_ADD", 6, row + 2, below, -yc, y, label="y")
    return x, y


def _uv(build, x, y, origin, size, texture_size, row):
    """The image coordinates of chart point (x, y) in the rectangle of nodes
    whose first node is texel `origin` and whose size is `size` texels:
    node i at the centre of texel origin + i, so u = (x0 + 0.5 + x (w − 1))
    / W; Blender puts an image file's first row at v = 1, so the texture is
    read at 1 − v."""
    width, height = texture_size
    (x0, y0), (w, h) = origin, size
    u = build.math("MULTIPLY_ADD", 6.5, row, x, (w - 1) / width, (x0 + 0.5) / width, label="u")
    v = build.math(
        "MULTIPLY_ADD", 6.5, row + 1, y, -(h - 1) / height, 1.0 - (y0 + 0.5) / height,
        label="v (Blender)",
    )
    uv = build.node("ShaderNodeCombineXYZ", 7, row, label="uv")
    build.link(u, uv.inputs["X"])
    build.link(v, uv.inputs["Y"])
    return uv.outputs["Vector"]


def _chart_uv(build, chart, atlas_size, x, cos, row):
    """The image coordinates of (thickness fraction x, cos θ) in one chart of
    the atlas: the export's mapping (docs/gpu.md) in math nodes, with the
    chart's numbers written into them. Returns the vector socket."""
    x, y = _mapping_xy(build, chart, x, cos, row)
    x0, y0, w, h = chart.rect
    return _uv(build, x, y, (x0, y0), (w, h), atlas_size, row)


def _atlas_uv(build, charts, atlas_size, d, c, row):
    """Version 3: the image coordinates of thickness d (nm, inside the
    range) at cos θ c (in [0, 1]) in the chart of `charts` (one side's, in
    the choice rule's order) that serves them. Every chart's (u, v) is
    computed, then chosen in closed form as the shader does: the first
    chart that serves (d, c), else the side's last band; one image lookup
    follows."""
    found = []
    for k, chart in enumerate(charts):
        at = row + 6 * k
        if chart.kind == "corner":
            x, y, serves = _corner_xy(build, chart, d, c, at)
        else:
            x, y = _band_xy(build, chart, d, c, at)
            serves = build.math("SUBTRACT", 4, at + 5, 1.0, build.math(
                "GREATER_THAN", 3.5, at + 5, c, chart.cos_hi), label=f"c ≤ {chart.cos_hi:.4g}")
        found.append((chart, serves, _uv(build, x, y, chart.rect[:2], chart.rect[2:], atlas_size, at)))
    last = max(k for k, (chart, _, _) in enumerate(found) if chart.kind == "band")
    uv = found[last][2]
    # From the last chart back to the first, each that serves replaces what
    # follows it: the first that serves wins.
    for k in reversed(range(last)):
        uv = _blend(build, uv, found[k][2], found[k][1], 8, row + 6 * k + 3, f"chart {k} serves")
    return uv


def _optical(build, chart, d, c, column, row):
    """p = d · s(c), s(c) = √max(1 − a (1 − c²), floor²): the optical
    thickness along which a band's fringes run."""
    if chart.a == 0.0:
        return d  # s = 1 (floor ≤ 1)
    t = build.math("MULTIPLY_ADD", column, row, build.math("MULTIPLY", column - 0.5, row, c, c),
                   chart.a, 1.0 - chart.a, label="1 − a (1 − c²)")
    s = build.math("SQRT", column + 1, row, build.math("MAXIMUM", column + 0.5, row, t,
                                                      chart.floor ** 2), label="s(c)")
    return build.math("MULTIPLY", column + 1.5, row, d, s, label="p = d s(c)")


def _log_e(build, value, column, row, label=None):
    """ln(value) (Blender's logarithm: 0 for value ≤ 0)."""
    return build.math("LOGARITHM", column, row, value, math.e, label=label)


def _band_xy(build, chart, d, c, row):
    """A band's (x, y): p on its log (or uniform) axis, cos θ (clamped to
    the band) on its warped axis, both clamped to [0, 1]."""
    clamp = build.node("ShaderNodeClamp", 3, row + 2, label="clamp to the band")
    build.link(c, clamp.inputs["Value"])
    clamp.inputs["Min"].default_value = chart.cos_lo
    clamp.inputs["Max"].default_value = chart.cos_hi
    ck = clamp.outputs["Result"]
    p = _optical(build, chart, d, ck, 4, row)
    u0, u1 = chart.p_warp(chart.p_lo_nm), chart.p_warp(chart.p_hi_nm)
    if u1 > u0:
        w = p
        if chart.p0_nm > 0.0:
            w = _log_e(build, build.math("MULTIPLY_ADD", 5.5, row, p, 1.0 / chart.p0_nm, 1.0), 6, row,
                       label="ln(1 + p / p0)")
        x = build.math("MULTIPLY_ADD", 6.5, row, w, 1.0 / (u1 - u0), -u0 / (u1 - u0), label="x")
        x.node.use_clamp = True
    else:
        x = build.math("MULTIPLY", 6.5, row, p, 0.0, label="x = 0 (one thickness)")
    v0, v1 = chart.c_warp(chart.cos_lo), chart.c_warp(chart.cos_hi)
    if v1 > v0:
        sign = chart.sign()
        t = build.math("MULTIPLY_ADD", 4, row + 1, ck, sign, -sign * chart.anchor, label="|c − anchor|")
        t = build.math("MAXIMUM", 4.5, row + 1, t, 0.0)
        if chart.offset > 0.0:
            g = _log_e(build, build.math("ADD", 5, row + 1, t, chart.offset), 5.5, row + 1)
        elif chart.offset == 0.0:
            g = build.math("SQRT", 5.5, row + 1, t)
        else:
            g = t
        # y = (σ g − W(lo)) / (W(hi) − W(lo))
        y = build.math("MULTIPLY_ADD", 6.5, row + 1, g, sign / (v1 - v0), -v0 / (v1 - v0), label="y")
        y.node.use_clamp = True
    else:
        y = build.math("MULTIPLY", 6.5, row + 1, ck, 0.0, label="y = 0 (one angle)")
    return x, y


def _corner_xy(build, chart, d, c, row):
    """The corner's polar (x, y) about zero thickness at grazing incidence,
    P = p / scale, ρ = √(P² + c²), φ = atan2(P, c): x = φ / (π/2), y = ρ /
    radius; and whether it serves (ρ < radius)."""
    pp = build.math("MULTIPLY", 5.5, row, _optical(build, chart, d, c, 4, row), 1.0 / chart.scale_nm,
                    label="P")
    rho = build.math("SQRT", 6.5, row + 1, build.math(
        "MULTIPLY_ADD", 6, row + 1, c, c, build.math("MULTIPLY", 5.5, row + 1, pp, pp)), label="ρ")
    phi = build.math("ARCTAN2", 6, row, pp, c, label="φ")
    x = build.math("MULTIPLY", 6.5, row, phi, 2.0 / math.pi, label="x")
    x.node.use_clamp = True
    y = build.math("MULTIPLY", 7, row + 1, rho, 1.0 / chart.radius, label="y")
    y.node.use_clamp = True
    serves = build.math("LESS_THAN", 7, row + 2, rho, chart.radius, label="ρ < radius")
    return x, y, serves


def _slice_offset(build, rough, slice_, row):
    """How far slice `slice_` (a float socket holding a whole number) lies
    from the texture's corner, in image coordinates: slices lie in rows of
    `columns`, slice s at (gutter + (s mod columns) · pitch_x, gutter +
    ⌊s / columns⌋ · pitch_y) texels; the half keeps the row off a rounding
    edge, as in the shader. Blender's v runs up the image, so the offset's
    v is negative."""
    columns = float(rough.columns)
    width, height = rough.size
    slice_row = build.math("FLOOR", 4, row, build.math("DIVIDE", 3.5, row, build.math(
        "ADD", 3, row, slice_, 0.5), columns), label="slice row")
    column = build.math("MULTIPLY_ADD", 4.5, row, slice_row, -columns, slice_, label="slice column")
    du = build.math("MULTIPLY_ADD", 5, row, column, rough.pitch[0] / width, rough.gutter / width,
                    label="slice u")
    dv = build.math("MULTIPLY_ADD", 5, row + 1, slice_row, -rough.pitch[1] / height,
                    -rough.gutter / height, label="slice v")
    offset = build.node("ShaderNodeCombineXYZ", 5.5, row, label="slice offset")
    build.link(du, offset.inputs["X"])
    build.link(dv, offset.inputs["Y"])
    return offset.outputs["Vector"]


def add_film_layer(material, export_dir, thickness_nm=None, coat=False, name=None):
    """Puts an export's film on top of a material whose surface is a Principled
    BSDF: the film's reflection lobe is added to the Principled BSDF, whose
    Base Color is multiplied by the film's transmittance (the light the film
    lets through to the base, once, at the viewing angle). Returns the film's
    group node.

    coat=False, the film over the base: the export's substrate is the base's
    own top medium (paint, plastic: e.g. n = 1.5), so the film's reflectance
    already holds that surface's reflection and the Principled's Specular IOR
    Level is set to 0; the film takes the Principled's Normal and Roughness.
    coat=True, the film as the coat: the base keeps its own specular layer
    (the film lies on a clear coat over it), the Principled's Coat Weight is
    set to 0 (the film replaces the coat) and the film takes its Coat Normal
    and Coat Roughness.

    The film's roughness follows the Principled's: above 0 (or driven by a
    node) the export needs the rough table (`irid export --rough`).

    Raises ValueError when the material's output is not fed by a Principled
    BSDF, ExportError for a bad export or a rough base with an export without
    the rough table; the material is unchanged then."""
    tree = material.node_tree
    outputs = [n for n in tree.nodes if n.bl_idname == "ShaderNodeOutputMaterial"] if tree else []
    out = next((n for n in outputs if n.is_active_output), outputs[0] if outputs else None)
    links = out.inputs["Surface"].links if out is not None else ()
    base = links[0].from_node if links else None
    if base is None or base.bl_idname != "ShaderNodeBsdfPrincipled":
        raise ValueError(f"material {material.name}: its surface is not a Principled BSDF")
    export = Export(export_dir)
    if thickness_nm is not None:
        export.thickness_fraction(thickness_nm)  # refuses one outside the range
    normal, roughness = ("Coat Normal", "Coat Roughness") if coat else ("Normal", "Roughness")
    if base.inputs[roughness].links:
        export.require_rough(f"the Principled BSDF's {roughness} is driven by a node")
    elif base.inputs[roughness].default_value > 0.0:
        export.require_rough(
            f"the Principled BSDF's {roughness} is {base.inputs[roughness].default_value:g}"
        )
    group = make_node_group(export, name=name or f"{material.name} film")
    build = _Builder(tree)
    x, y = base.location
    film = tree.nodes.new("ShaderNodeGroup")
    film.node_tree = group
    film.label = "irid film"
    film.location = (x - 500.0, y + 300.0)
    if thickness_nm is not None:
        film.inputs["Thickness nm"].default_value = float(thickness_nm)
    if base.inputs[normal].links:
        build.link(base.inputs[normal].links[0].from_socket, film.inputs["Normal"])
    if export.rough is None:
        pass  # the base's roughness is 0 (checked above): the film is a mirror too
    elif base.inputs[roughness].links:
        build.link(base.inputs[roughness].links[0].from_socket, film.inputs["Roughness"])
    else:
        film.inputs["Roughness"].default_value = base.inputs[roughness].default_value
    through = tree.nodes.new("ShaderNodeVectorMath")
    through.operation = "MULTIPLY"
    through.label = "base colour × film transmittance"
    through.location = (x - 250.0, y + 100.0)
    colour = base.inputs["Base Color"]
    if colour.links:
        build.link(colour.links[0].from_socket, through.inputs[0])
    else:
        through.inputs[0].default_value = tuple(colour.default_value)[:3]
    build.link(film.outputs["Transmittance"], through.inputs[1])
    build.link(through.outputs["Vector"], colour)
    off = base.inputs["Coat Weight" if coat else "Specular IOR Level"]
    for link in list(off.links):
        tree.links.remove(link)
    off.default_value = 0.0
    add = tree.nodes.new("ShaderNodeAddShader")
    add.location = (x + 300.0, y)
    build.link(film.outputs["Reflection"], add.inputs[0])
    build.link(base.outputs["BSDF"], add.inputs[1])
    build.link(add.outputs["Shader"], out.inputs["Surface"])
    return film


# Add-on: File > Import > irid film (film.json).


class IRID_OT_import_film(bpy.types.Operator):
    """Build a material from an irid export (film.json) and assign it to the selected objects"""

    bl_idname = "import_scene.irid_film"
    bl_label = "Import irid film"
    bl_options = {"REGISTER", "UNDO"}

    filepath: bpy.props.StringProperty(subtype="FILE_PATH")
    filter_glob: bpy.props.StringProperty(default="film.json", options={"HIDDEN"})
    use_thickness: bpy.props.BoolProperty(
        name="Constant thickness",
        description="Use one thickness in nm; off leaves the 0-1 Thickness socket to a texture",
        default=True,
    )
    thickness_nm: bpy.props.FloatProperty(name="Thickness (nm)", default=300.0, min=0.0)
    roughness: bpy.props.FloatProperty(name="Roughness", default=0.0, min=0.0, max=1.0)

    def execute(self, context):
        meshes = [obj for obj in context.selected_objects if obj.type == "MESH"]
        if not meshes:
            self.report({"ERROR"}, "No mesh is selected: select the meshes to put the film on")
            return {"CANCELLED"}
        try:
            material = make_material(
                os.path.dirname(self.filepath),
                thickness_nm=self.thickness_nm if self.use_thickness else None,
                roughness=self.roughness,
            )
        except ValueError as e:
            self.report({"ERROR"}, str(e))
            return {"CANCELLED"}
        # The film takes the active material slot; the mesh's other slots
        # (and the faces assigned to them) stay as they were.
        for obj in meshes:
            if obj.material_slots:
                obj.active_material = material
            else:
                obj.data.materials.append(material)
        self.report(
            {"INFO"},
            f"Built material {material.name}, in the active slot of {len(meshes)} mesh"
            f"{'' if len(meshes) == 1 else 'es'}",
        )
        return {"FINISHED"}

    def invoke(self, context, event):
        context.window_manager.fileselect_add(self)
        return {"RUNNING_MODAL"}


def _menu_import(self, context):
    self.layout.operator(IRID_OT_import_film.bl_idname, text="irid film (film.json)")


def register():
    bpy.utils.register_class(IRID_OT_import_film)
    bpy.types.TOPBAR_MT_file_import.append(_menu_import)


def unregister():
    bpy.types.TOPBAR_MT_file_import.remove(_menu_import)
    bpy.utils.unregister_class(IRID_OT_import_film)
