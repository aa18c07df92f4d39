"""The atlas's charts (docs/gpu.md, "The mapping"; src/atlas/chart.rs and
gpu/src/generate.rs hold the same mapping in Rust and WGSL): each chart's
numbers from film.json, its closed-form (thickness, cos θ) -> (x, y) in
Python, and the choice rule. The node graph (nodes.py) computes the same
in math nodes; these are the reference its tests compare with."""

import math

from .film import ExportError, require_number, require_object


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
        params = require_object(chart, "params", f"irid export {where}")
        number = lambda key: require_number(params, key, f"{where}.params")  # noqa: E731
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
        self.rect = check_rect([number(key) for key in ("x0", "y0", "width", "height")], where, atlas_size)
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


def check_rect(rect, where, atlas_size):
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
