"""An export directory checked: film.json by the reader rule (film.py),
then what the node graph needs from it: the atlas's charts per side, the
texture files, the rough table's slices, the substrate's index. No bpy
here."""

import math
import os

from .charts import AtlasChart, check_rect
from .film import (
    ExportError,
    file_in,
    is_whole,
    read_film,
    require_object,
    thickness_range,
)

# Wavelength at which a transmitting film's refraction index is taken: the
# one irid grades the substrate's critical angle at (docs/lut-format.md).
IOR_WAVELENGTH_NM = 550.0
TABLES = ("reflectance", "transmittance")
# The white Blender Cycles renders in: a flat spectrum is (1, 1, 1)
# (docs/color.md); `irid export --white e` makes that export.
BLENDER_WHITE = "e"


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
        texture = require_object(rough, "texture", f"irid export {where}")
        tiling = require_object(rough, "tiling", f"irid export {where}")
        atlas = require_object(rough, "atlas", f"irid export {where}")
        self.path = file_in(directory, texture.get("file"), f"{where}.texture.file")
        whole = is_whole
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
        self.thickness_min_nm, self.thickness_max_nm = thickness_range(
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
            check_rect(placed, f"{where}: slice {s}", self.size)

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
        film = read_film(film_path)
        self.film = film
        where = film_path
        self.version = film["version"]
        texture = film["texture"]
        self.size = (texture["width"], texture["height"])
        self.charts = [
            AtlasChart(c if isinstance(c, dict) else {}, f"{where}: charts[{k}]", self.size)
            for k, c in enumerate(film["charts"])
        ]
        # Several charts per side, in the order the choice rule reads them:
        # front and back are tuples of AtlasChart (the same tuple when both
        # sides read the same charts).
        sides = film["sides"]
        self.front = self._charts_of(sides, "front", where)
        self.back = None
        if sides.get("back") is not None:
            self.back = self._charts_of(sides, "back", where)
            if self.back == self.front:
                self.back = self.front
        self.thickness_min_nm, self.thickness_max_nm = thickness_range(
            film["domain"], f"{where}: domain.thickness_nm"
        )
        self.opaque = film["opaque"]
        files = require_object(texture, "files", f"irid export {where}", "texture.")
        self.paths = {
            table: file_in(self.directory, files.get(table), f"{where}: texture.files.{table}")
            for table in TABLES
        }
        self.white = film["white"]
        if self.white != BLENDER_WHITE:
            raise ExportError(
                f"irid export {where}: white {self.white!r}, but Blender's colours are white "
                "E (a flat spectrum is 1, 1, 1): export it again with `--white e`"
            )
        self.stack = film["stack"]
        # The rough table (`irid export --rough`): null without it.
        rough = film.get("rough")
        self.rough = None
        if rough is not None:
            if rough.get("light_from") != "ambient":
                raise ExportError(
                    f"irid export {where}: rough.light_from {rough.get('light_from')!r}, "
                    "expected 'ambient'"
                )
            self.rough = Rough(rough, self.directory, where)
        self.label = os.path.basename(self.directory.rstrip(os.sep)) or "film"

    def _charts_of(self, sides, side, where):
        """The side's charts, in the atlas's order (the order the
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
