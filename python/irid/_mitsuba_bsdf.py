"""The Dr.Jit side of ``irid_film`` (irid.mitsuba makes the class once a
Mitsuba variant is set): the film's R and T per wavelength, from irid's
solver through numpy or from a spectral table looked up in Dr.Jit, and the
BSDF's sampling, evaluation and density."""

import json

import drjit as dr
import mitsuba as mi
import numpy as np

from . import Stack
from .mitsuba import MAX_THICKNESS_NM, SPECTRAL_RANGE_NM, FilmError, _FilmSetup, ggx_lambda

#: The smallest α of Mitsuba's MicrofacetDistribution (it clamps below).
MIN_GGX_ALPHA = 1e-4

_SYMBOLIC = (
    "irid_film: a film without a table was traced in a symbolic Dr.Jit loop or call, where its solver "
    "cannot run (it runs between kernels); it gives zeros there. Render in the thread that called "
    "irid.mitsuba.register() (which turns symbolic loops and calls off), or give the film a table. "
    "(Dr.Jit traces every live BSDF, so a film of another, still referenced scene also shows this.)"
)


def make_class(variant, symbolic):
    """The ``irid_film`` plugin class for ``variant``, or a loader that
    refuses the variant with one line. ``symbolic``: Dr.Jit's symbolic
    loops and calls are kept, so only table films can be served."""
    if not mi.is_spectral or mi.is_polarized:

        def refuse(_props):
            raise FilmError(
                f"variant {variant}",
                "irid_film needs an unpolarized spectral variant (scalar_spectral, llvm_ad_spectral): "
                "interference is solved per wavelength, and no RGB triple stands for a film's "
                "spectrum under every light",
            )

        return refuse
    return _make_bsdf(symbolic)


def _not(mask):
    """Logical not of a mask: a Python bool in the scalar variants."""
    return (not mask) if isinstance(mask, bool) else ~mask


def _channel_mean(x):
    total = x[0]
    for i in range(1, len(x)):
        total = total + x[i]
    return total / len(x)


def _sanitized(thickness, cos_theta, wavelengths, front, active):
    """Values the solver accepts in every lane, inactive ones included
    (their results are discarded)."""
    cos_theta = dr.select(active, dr.clip(cos_theta, 0.0, 1.0), 1.0)
    ok = active & dr.isfinite(thickness)
    thickness = dr.select(ok, dr.clip(thickness, 0.0, MAX_THICKNESS_NM), 0.0)
    wavelengths = dr.select(active, dr.clip(wavelengths, *SPECTRAL_RANGE_NM), 550.0)
    front = dr.select(active, front, True)
    return thickness, cos_theta, wavelengths, front


def _warn_symbolic(response):
    if not response.warned:
        mi.Log(mi.LogLevel.Warn, _SYMBOLIC)
        response.warned = True
    return dr.zeros(mi.UnpolarizedSpectrum), dr.zeros(mi.UnpolarizedSpectrum)


#: The step of the central difference in cos θ on the solver path (float64:
#: its truncation and rounding errors are both below 1e-8 relative, far
#: under the float32 the render carries).
COS_STEP = 1e-5


class _SolverLanes:
    """A wavefront's lanes in numpy (float64), one row per wavelength, and
    irid's solver on them: one call per side of the film."""

    def __init__(self, stack, layer, thickness, cos_theta, wavelengths, front, active):
        self.stack, self.layer = stack, layer
        thickness, cos_theta, wavelengths, front = _sanitized(thickness, cos_theta, wavelengths, front, active)
        self.w = np.asarray(wavelengths, dtype=np.float64)
        self.c, self.d, self.f, self.a = (
            np.broadcast_to(np.asarray(x, dtype=t), self.w.shape)
            for x, t in ((cos_theta, np.float64), (thickness, np.float64), (front, bool), (active, bool))
        )

    def response(self, cos_theta=None):
        c = self.c if cos_theta is None else cos_theta
        r, t = np.zeros(self.w.shape), np.zeros(self.w.shape)
        # Only the lanes that ask: a wavefront holds every path, finished or not.
        for side, lanes in (("ambient", self.f & self.a), ("substrate", ~self.f & self.a)):
            if lanes.any():
                r[lanes], t[lanes] = self.stack.response(c[lanes], self.w[lanes], self.d[lanes], layer=self.layer, side=side)
        return r, t

    def cos_derivative(self):
        """d(R, T)/d cos θ: a central difference (one-sided at 0 and 1)."""
        up, down = np.minimum(self.c + COS_STEP, 1.0), np.maximum(self.c - COS_STEP, 0.0)
        (r1, t1), (r0, t0) = self.response(up), self.response(down)
        step = np.where(self.a, up - down, 1.0)
        return (r1 - r0) / step, (t1 - t0) / step

    def thickness_derivative(self):
        """d(R, T)/d(thickness) of the varying layer at every lane: irid's
        exact derivative (``Stack.solve(gradient=True)``), one solve of one
        point per lane, the stack as the light meets it (reversed from
        the substrate)."""
        d_r, d_t = np.zeros(self.w.shape), np.zeros(self.w.shape)
        template = json.loads(self.stack.to_json())
        count = len(template["layers"])
        # Stack.solve takes angles below 90°; at grazing incidence R → 1 and
        # its derivative → 0, which cos θ = 1e-7 gives within float32.
        angles = np.degrees(np.arccos(np.clip(self.c, 1e-7, 1.0)))
        stacks = {}
        for index in zip(*np.nonzero(self.a)):
            side, d = bool(self.f[index]), float(self.d[index])
            if (side, d) not in stacks:
                stacks[(side, d)] = _oriented_stack(template, self.layer, d, side)
            stack, layer_index = stacks[(side, d)]
            solved = stack.solve([self.w[index]], [angles[index]], gradient=True)
            d_r[index] = solved["dR_dd"][layer_index, 0, 0]
            d_t[index] = solved["dT_dd"][layer_index, 0, 0]
        return d_r, d_t


def _oriented_stack(template, layer, thickness, front):
    """The stack of JSON ``template`` with layer ``layer`` (1-based from the
    ambient) at ``thickness``, as light from the ambient (``front``) or
    from the substrate meets it, and that layer's 0-based index in it."""
    stack = json.loads(json.dumps(template))
    stack["layers"][layer - 1]["thickness_nm"] = thickness
    index = layer - 1
    if not front:
        stack["ambient"], stack["substrate"] = stack["substrate"], stack["ambient"]
        stack["layers"].reverse()
        index = len(stack["layers"]) - layer
    return Stack.from_json(json.dumps(stack)), index


def _spectrum(x):
    return mi.UnpolarizedSpectrum(np.asarray(x, dtype=np.float32))


class _SolverOp(dr.CustomOp):
    """irid's solver as a Dr.Jit operation: the values from numpy, and their
    derivatives with respect to the thickness (irid's exact derivative)
    and cos θ (a float64 central difference of the solver, for gradients
    that reach the film through the direction: a roughness, a
    microfacet's normal)."""

    def eval(self, lanes_of, wants, thickness, cos_theta):
        # dr.custom hands eval detached inputs: which ones carry gradients
        # comes from the caller.
        self.lanes = lanes_of(thickness, cos_theta)
        self.wants = wants
        self.derivatives = {}
        r, t = self.lanes.response()
        return _spectrum(r), _spectrum(t)

    def _derivative(self, name):
        if name not in self.derivatives:
            pair = self.lanes.thickness_derivative() if name == "thickness" else self.lanes.cos_derivative()
            self.derivatives[name] = tuple(_spectrum(x) for x in pair)
        return self.derivatives[name]

    def forward(self):
        out_r, out_t = dr.zeros(mi.UnpolarizedSpectrum), dr.zeros(mi.UnpolarizedSpectrum)
        for name in ("thickness", "cos_theta"):
            if self.wants[name]:
                d_r, d_t = self._derivative(name)
                grad = self.grad_in(name)
                out_r, out_t = out_r + d_r * grad, out_t + d_t * grad
        self.set_grad_out((out_r, out_t))

    def backward(self):
        grad_r, grad_t = self.grad_out()
        for name in ("thickness", "cos_theta"):
            if self.wants[name]:
                d_r, d_t = self._derivative(name)
                self.set_grad_in(name, dr.sum(grad_r * d_r + grad_t * d_t))

    def name(self):
        return "irid_film solver"


class _SolverResponse:
    """R and T from irid's solver: the lanes' values go to numpy, one call
    per side of the film, and come back as a spectrum (a Dr.Jit custom
    operation, so that gradients through cos θ flow)."""

    def __init__(self, setup):
        self.stack, self.layer = setup.stack, setup.layer
        self.jit = dr.is_jit_v(mi.Float)
        self.warned = False

    def __call__(self, thickness, cos_theta, wavelengths, front, active):
        if self.jit and dr.flag(dr.JitFlag.SymbolicScope):
            return _warn_symbolic(self)

        def lanes_of(d, c):
            return _SolverLanes(self.stack, self.layer, d, c, wavelengths, front, active)

        if self.jit and (dr.grad_enabled(thickness) or dr.grad_enabled(cos_theta)):
            wants = {"thickness": dr.grad_enabled(thickness), "cos_theta": dr.grad_enabled(cos_theta)}
            return dr.custom(_SolverOp, lanes_of, wants, thickness, cos_theta)
        r, t = lanes_of(thickness, cos_theta).response()
        return _spectrum(r), _spectrum(t)


def _locate(nodes, size, ends, x):
    """The interval of an axis of ``size`` float32 ``nodes`` (a Dr.Jit
    array) holding ``x`` (clamped to ``ends``) and the weight of its upper
    node, as irid's sampler finds them: a Dr.Jit expression of ``x``, so
    that gradients flow through the interpolation."""
    if size == 1:
        return mi.UInt32(0), mi.Float(0.0)
    x = dr.clip(x, *ends)
    i = dr.binary_search(0, size - 2, lambda j: dr.gather(mi.Float, nodes, j + 1) < x)
    x0, x1 = dr.gather(mi.Float, nodes, i), dr.gather(mi.Float, nodes, i + 1)
    return i, dr.clip((x - x0) / (x1 - x0), 0.0, 1.0)


class _GridLookup:
    """A grid table (format versions 2 and 3) in Dr.Jit: a binary search per
    axis (irid's axes are not uniform) and eight gathers, trilinear as
    irid's sampler."""

    def __init__(self, lut):
        axes = lut.header["axes"]
        self.sizes = [len(a["nodes"]) for a in axes]  # thickness, cos θ, wavelength
        self.ends = [(float(np.float32(a["nodes"][0])), float(np.float32(a["nodes"][-1]))) for a in axes]
        self.nodes = [mi.Float(np.asarray(a["nodes"], dtype=np.float32)) for a in axes]
        data = lut.data
        self.reflectance = mi.Float(np.ascontiguousarray(data[..., 0]).ravel())
        self.transmittance = mi.Float(np.ascontiguousarray(data[..., 1]).ravel())

    def __call__(self, thickness, cos_theta, wavelength):
        (ti, tf), (ci, cf), (wi, wf) = (
            _locate(self.nodes[k], self.sizes[k], self.ends[k], x) for k, x in enumerate((thickness, cos_theta, wavelength))
        )
        nt, nc = self.sizes[0], self.sizes[1]
        # An axis of one node (a table of one thickness) has no upper node.
        st, sc, sw = (int(n > 1) for n in self.sizes)
        r, t = mi.Float(0.0), mi.Float(0.0)
        for dw, weight_w in ((0, 1.0 - wf), (sw, wf)):
            for dc, weight_c in ((0, 1.0 - cf), (sc, cf)):
                row = ((wi + dw) * nc + ci + dc) * nt + ti
                for dt, weight_t in ((0, 1.0 - tf), (st, tf)):
                    weight = weight_w * weight_c * weight_t
                    r += weight * dr.gather(mi.Float, self.reflectance, row + dt)
                    t += weight * dr.gather(mi.Float, self.transmittance, row + dt)
        return r, t


def _chart_uv(chart, d, c):
    """An atlas chart's normalized coordinates (u, v) of (d, c), and for a
    corner whether it serves them (as ``texel_f32`` in src/atlas/chart.rs
    maps them, in Dr.Jit arithmetic)."""
    f32 = np.float32
    a, floor = (f32(chart["optical"][k]) for k in ("a", "floor"))
    coords = chart["coords"]

    def s(c):
        return dr.sqrt(dr.maximum(1.0 - float(a) * (1.0 - c * c), float(floor * floor)))

    if coords["kind"] == "corner":
        scale, radius = float(f32(coords["scale_nm"])), float(f32(coords["radius"]))
        pp = d * s(c) / scale
        rho = dr.sqrt(pp * pp + c * c)
        # atan2(0, 0) reads φ = 0, as the shaders do.
        phi = dr.select(rho > 0.0, dr.atan2(pp, c), 0.0)
        return dr.clip(phi / (np.pi / 2), 0.0, 1.0), dr.clip(rho / radius, 0.0, 1.0), rho < radius
    p_axis, c_axis = coords["p"], coords["c"]
    p0, lo_nm, hi_nm = (f32(p_axis[k]) for k in ("p0_nm", "lo_nm", "hi_nm"))
    lo, hi, anchor, offset = (f32(c_axis[k]) for k in ("lo", "hi", "anchor", "offset"))
    c = dr.clip(c, float(lo), float(hi))
    p = d * s(c)

    def u_warp(p):
        if p0 > 0.0:
            return dr.log(1.0 + dr.maximum(p, 0.0) / float(p0))
        return p

    def v_warp(c):
        t = dr.abs(c - float(anchor))
        g = dr.log(t + float(offset)) if offset > 0.0 else (dr.sqrt(t) if offset == 0.0 else t)
        return g if lo >= anchor else -g

    def v_warp_f32(c):
        t = abs(c - anchor)
        g = np.log(t + offset) if offset > 0.0 else (np.sqrt(t) if offset == 0.0 else t)
        return float(g if lo >= anchor else -g)

    u0, u1 = (float(np.log(f32(1.0) + x / p0)) if p0 > 0.0 else float(x) for x in (lo_nm, hi_nm))
    v0, v1 = v_warp_f32(lo), v_warp_f32(hi)
    u = dr.clip((u_warp(p) - u0) / (u1 - u0), 0.0, 1.0) if u1 > u0 else mi.Float(0.0)
    v = dr.clip((v_warp(c) - v0) / (v1 - v0), 0.0, 1.0) if v1 > v0 else mi.Float(0.0)
    return u, v, None


class _AtlasLookup:
    """An atlas table (format version 4, docs/lut-format.md) in Dr.Jit,
    operation for operation irid's sampler in float32 (``locate_f32`` and
    ``texel_f32`` in src/atlas/, ``Lut::sample_spectral``): each wavelength
    node's block read at the same d/λ, the chart chosen by the header's
    rule, the chart's coordinates, a bilinear fetch; then linear in λ. Every
    step from the thickness and cos θ to the texel position is Dr.Jit
    arithmetic, so gradients flow through the lookup."""

    def __init__(self, lut):
        header = lut.header
        atlas, axes = header["atlas"], header["axes"]
        self.width, self.height = atlas["width"], atlas["height"]
        self.atlas_range = tuple(float(np.float32(x)) for x in atlas["thickness_nm"])
        self.thickness_range = tuple(float(np.float32(x)) for x in (axes[0]["nodes"][0], axes[0]["nodes"][-1]))
        wl = np.asarray(axes[2]["nodes"], dtype=np.float32)
        self.wl_size, self.wl_ends, self.wl_nodes = len(wl), (float(wl[0]), float(wl[-1])), mi.Float(wl)
        self.charts = [c for c in atlas["charts"] if c["side"] == 0]
        data = np.asarray(lut.data, dtype=np.float32)  # (wavelength node, row, column, R and T)
        self.rows = data.shape[0] * data.shape[1]
        self.reflectance = mi.Float(np.ascontiguousarray(data[..., 0]).ravel())
        self.transmittance = mi.Float(np.ascontiguousarray(data[..., 1]).ravel())

    def _texel(self, d, c):
        """The texel position (x, y) of (d, c) on the ambient side's charts."""
        d = dr.clip(d, *self.atlas_range)
        c = dr.clip(c, 0.0, 1.0)
        done = mi.Bool(False)
        x, y = mi.Float(0.0), mi.Float(0.0)
        last = None
        for chart in self.charts:
            u, v, in_corner = _chart_uv(chart, d, c)
            rect = chart["rect"]
            tx = rect["x"] + 0.5 + u * (rect["width"] - 1.0)
            ty = rect["y"] + 0.5 + v * (rect["height"] - 1.0)
            if in_corner is not None:
                take = ~done & in_corner
            else:
                take = ~done & (c <= float(np.float32(chart["coords"]["c"]["hi"])))
                last = (tx, ty)
            x, y = dr.select(take, tx, x), dr.select(take, ty, y)
            done |= take
        if last is not None:
            x, y = dr.select(done, x, last[0]), dr.select(done, y, last[1])
        return x, y

    def _bilinear(self, x, y, block):
        """The bilinear fetch at texel position (x, y) of wavelength block
        ``block``, texel centres at i + 0.5, clamped to the image's edge."""

        def split(t, n):
            t = t - 0.5
            lower = dr.floor(t)
            i = mi.Int32(lower)
            return t - lower, mi.UInt32(dr.clip(i, 0, n - 1)), mi.UInt32(dr.clip(i + 1, 0, n - 1))

        fx, x0, x1 = split(x, self.width)
        fy, y0, y1 = split(y + mi.Float(block) * self.height, self.rows)
        out = []
        for image in (self.reflectance, self.transmittance):
            a, b = dr.gather(mi.Float, image, y0 * self.width + x0), dr.gather(mi.Float, image, y0 * self.width + x1)
            c, d = dr.gather(mi.Float, image, y1 * self.width + x0), dr.gather(mi.Float, image, y1 * self.width + x1)
            top, bottom = a + fx * (b - a), c + fx * (d - c)
            out.append(top + fy * (bottom - top))
        return out

    def __call__(self, thickness, cos_theta, wavelength):
        k, fz = _locate(self.wl_nodes, self.wl_size, self.wl_ends, wavelength)
        upper = dr.minimum(k + 1, self.wl_size - 1)
        lo, hi = dr.gather(mi.Float, self.wl_nodes, k), dr.gather(mi.Float, self.wl_nodes, upper)
        d = dr.clip(thickness, *self.thickness_range)
        lam = dr.clip(wavelength, lo, self.wl_ends[1])
        r_lo, t_lo = self._bilinear(*self._texel(d * (lo / lam), cos_theta), k)
        r_hi, t_hi = self._bilinear(*self._texel(d * (hi / lam), cos_theta), upper)
        return r_lo + fz * (r_hi - r_lo), t_lo + fz * (t_hi - t_lo)


class _TableResponse:
    """R and T from a spectral table, interpolated as irid's sampler does
    (linear in each axis value, clamped at the ends): in Dr.Jit for a grid
    or an atlas table in the JIT variants (so the lookup runs in symbolic
    mode and Dr.Jit differentiates it), irid's own sampler in the scalar
    variant. Light from a lossless substrate through lossless layers is
    served by reciprocity: T is the same at the corresponding angle in the
    ambient, and R = 1 − T (total internal reflection where no such angle
    exists)."""

    def __init__(self, setup):
        self.lut = setup.table
        self.jit = dr.is_jit_v(mi.Float)
        self.eta_per_nm = setup.eta_per_nm
        if self.jit:
            self.eta_nodes = mi.Float(self.eta_per_nm)
            self.lookup = _AtlasLookup(self.lut) if "atlas" in self.lut.header else _GridLookup(self.lut)

    def _eta(self, wavelength):
        """n_substrate / n_ambient at ``wavelength`` (1 nm nodes, linear)."""
        x = dr.clip(wavelength - SPECTRAL_RANGE_NM[0], 0.0, len(self.eta_per_nm) - 1.0)
        if not self.jit:
            return float(np.interp(x, np.arange(len(self.eta_per_nm)), self.eta_per_nm))
        i = mi.UInt32(dr.minimum(dr.floor(x), len(self.eta_per_nm) - 2.0))
        f = x - mi.Float(i)
        return dr.lerp(dr.gather(mi.Float, self.eta_nodes, i), dr.gather(mi.Float, self.eta_nodes, i + 1), f)

    def __call__(self, thickness, cos_theta, wavelengths, front, active):
        thickness, cos_theta, wavelengths, front = _sanitized(thickness, cos_theta, wavelengths, front, active)
        r, t = [], []
        for k in range(len(wavelengths)):
            # From the substrate: the angle in the ambient with the same
            # tangential index (none past the critical angle).
            eta = self._eta(wavelengths[k])
            sin2_ambient = (1.0 - cos_theta * cos_theta) * eta * eta
            cos_ambient = dr.select(front, cos_theta, dr.safe_sqrt(1.0 - sin2_ambient))
            if self.jit:
                r_k, t_k = self.lookup(thickness, cos_ambient, wavelengths[k])
            else:
                r_k, t_k = (float(v) for v in self.lut.sample(thickness, cos_ambient, wavelengths[k]))
            t_k = dr.select(front | (sin2_ambient < 1.0), t_k, 0.0)
            r.append(dr.select(front, r_k, 1.0 - t_k))
            t.append(t_k)
        return mi.UnpolarizedSpectrum(*r), mi.UnpolarizedSpectrum(*t)


class _FilmLoading:
    """Reading a film's properties into the BSDF's state: the solver or
    table behind R and T, the parameters, and the lobes Mitsuba is told
    about. One of the pieces of the class _make_bsdf builds, whose
    ``_flags`` are its variant's BSDFFlags."""

    def _load(self, props, symbolic):
        flags = self._flags
        values = {key: props[key] for key in props.keys()}
        values["type"] = "irid_film"
        setup = _FilmSetup.from_values(values)
        self.setup = setup
        if isinstance(setup.thickness, mi.Texture):
            self.thickness = setup.thickness
        elif isinstance(setup.thickness, float):
            self.thickness = dr.opaque(mi.Float, setup.thickness)
        else:
            raise FilmError("thickness_nm", f"expected a number or a texture, got {type(setup.thickness).__name__}")
        if setup.textured_roughness and not isinstance(setup.roughness, mi.Texture):
            raise FilmError("roughness", f"expected a number or a texture, got {type(setup.roughness).__name__}")
        self.roughness = setup.roughness if setup.textured_roughness else dr.opaque(mi.Float, setup.roughness)
        self.transmissive = setup.transmissive
        self.eta = setup.eta
        self.rough = setup.rough
        if setup.table is None and dr.is_jit_v(mi.Float) and symbolic:
            raise FilmError(
                "table",
                "missing: irid.mitsuba.register(symbolic=True) keeps Dr.Jit's symbolic loops, in which "
                "only a table can be looked up (the solver runs between kernels); give a spectral "
                "table or register without symbolic=True",
            )
        self.response = _TableResponse(setup) if setup.table is not None else _SolverResponse(setup)
        sides = flags.FrontSide | flags.BackSide if self.transmissive else flags.FrontSide
        reflection = (flags.GlossyReflection if self.rough else flags.DeltaReflection) | sides
        transmission = (
            (flags.GlossyTransmission if self.rough else flags.DeltaTransmission)
            | flags.FrontSide
            | flags.BackSide
            | flags.NonSymmetric
        )
        self.m_components = [reflection] + ([transmission] if self.transmissive else [])
        self.m_flags = reflection | (transmission if self.transmissive else 0)
        if setup.textured_roughness or isinstance(self.thickness, mi.Texture):
            self.m_flags = self.m_flags | flags.SpatiallyVarying

    def _description(self):
        """The one line Mitsuba prints for the BSDF."""
        s = self.setup
        source = "table" if s.table is not None else "solver"
        thickness, roughness = (
            "texture" if isinstance(v, mi.Texture) else f"{float(v[0]) if dr.is_array_v(v) else float(v):g}" for v in (self.thickness, self.roughness)
        )
        return (
            f"IridFilm[layer={s.layer}, thickness_nm={thickness}, roughness={roughness}, "
            f"{source}, {'transmissive' if self.transmissive else 'opaque'}]"
        )


class _FilmLobes:
    """The film's R and T at an incidence, the choice between its
    reflection and transmission lobes, and the smooth film's sampling
    (delta lobes). One of the pieces of the class _make_bsdf builds."""

    def film(self, si, cos_theta, front, active):
        """The film's (R, T) at ``cos_theta`` for light from the front
        (ambient) or back (substrate) side, per wavelength of ``si``."""
        if isinstance(self.thickness, mi.Texture):
            thickness = self.thickness.eval_1(si, active)
        else:
            thickness = mi.Float(self.thickness)
        return self.response(thickness, cos_theta, si.wavelengths, front, active)

    def lobe_choice(self, ctx, r, t, cos_in, front, glossy):
        """The probability of sampling reflection rather than transmission
        (the spectrum's mean R against its mean T), or None when neither
        lobe is enabled."""
        flags = self._flags
        reflect_flag = flags.GlossyReflection if glossy else flags.DeltaReflection
        transmit_flag = flags.GlossyTransmission if glossy else flags.DeltaTransmission
        has_r = ctx.is_enabled(reflect_flag, 0)
        has_t = self.transmissive and ctx.is_enabled(transmit_flag, 1)
        if not has_r and not has_t:
            return None
        if not has_t:
            return mi.Float(1.0)
        # Past the critical angle of the directions' own refraction no
        # ray can be sent through, whatever a dispersive index says.
        eta_ti = dr.select(front, 1.0 / self.eta, self.eta)
        tir = (1.0 - cos_in * cos_in) * eta_ti * eta_ti >= 1.0
        r_mean = _channel_mean(r)
        t_mean = dr.select(tir, 0.0, _channel_mean(t))
        total = r_mean + t_mean
        p_r = dr.select(total > 0.0, r_mean / dr.maximum(total, 1e-30), 1.0)
        return p_r if has_r else mi.Float(0.0)

    def incidence(self, si, active):
        """cos θ_i, whether light comes from the ambient side, and the
        lanes this film answers (no grazing ray; an opaque film's back
        side is black)."""
        cos_i = mi.Frame3f.cos_theta(si.wi)
        front = cos_i > 0.0
        active = active & (cos_i != 0.0)
        if not self.transmissive:
            active = active & front
        return cos_i, front, active

    def lobe_sample(self, selected_r, eta_it, glossy):
        """A BSDFSample3f naming the lobe chosen (reflection or refraction)."""
        flags = self._flags
        bs = dr.zeros(mi.BSDFSample3f)
        reflection = flags.GlossyReflection if glossy else flags.DeltaReflection
        transmission = flags.GlossyTransmission if glossy else flags.DeltaTransmission
        bs.eta = dr.select(selected_r, 1.0, eta_it)
        bs.sampled_component = dr.select(selected_r, mi.UInt32(0), mi.UInt32(1))
        bs.sampled_type = dr.select(selected_r, mi.UInt32(+reflection), mi.UInt32(+transmission))
        return bs

    def choose_lobe(self, ctx, si, cos_in, front, active, sample1, glossy):
        """The film's (R, T) at ``cos_in`` (signed: cos θ_i, or wi·m for a
        microfacet), the lobe ``sample1`` picks, and the refraction's
        cos θ_t and η_ti there; None when no lobe is enabled."""
        r, t = self.film(si, dr.abs(cos_in), front, active)
        p_r = self.lobe_choice(ctx, r, t, dr.abs(cos_in), front, glossy)
        if p_r is None:
            return None
        selected_r = sample1 < p_r
        _, cos_t, eta_it, eta_ti = mi.fresnel(cos_in, self.eta)
        bs = self.lobe_sample(selected_r, eta_it, glossy)
        return r, t, p_r, selected_r, cos_t, eta_ti, bs

    def radiance_scale(self, ctx, eta_ti):
        return dr.square(eta_ti) if ctx.mode == mi.TransportMode.Radiance else 1.0

    def sample_smooth(self, ctx, si, sample1, active):
        cos_i, front, active = self.incidence(si, active)
        chosen = self.choose_lobe(ctx, si, cos_i, front, active, sample1, glossy=False)
        if chosen is None:
            return dr.zeros(mi.BSDFSample3f), dr.zeros(mi.Spectrum)
        r, t, p_r, selected_r, cos_t, eta_ti, bs = chosen
        bs.wo = dr.select(selected_r, mi.reflect(si.wi), mi.refract(si.wi, cos_t, eta_ti))
        bs.pdf = dr.select(selected_r, p_r, 1.0 - p_r)
        active = active & (bs.pdf > 0.0)
        weight = dr.select(selected_r, r, t * self.radiance_scale(ctx, eta_ti)) / dr.maximum(bs.pdf, 1e-30)
        return bs, dr.select(active, mi.Spectrum(weight), 0.0)


class _GgxLobes:
    """The rough film: GGX microfacets, α = roughness², height-correlated
    Smith G2, each facet reflecting and transmitting as the smooth film
    does (_FilmLobes, a piece of the same class)."""

    def alpha(self, si, active):
        """GGX's α = roughness² at ``si`` (Mitsuba's GGX takes no α below
        1e-4, roughness 0.01; the masking uses the same α, so the lobe
        is one GGX throughout)."""
        if isinstance(self.roughness, mi.Texture):
            roughness = self.roughness.eval_1(si, active)
        else:
            roughness = mi.Float(self.roughness)
        roughness = dr.clip(dr.select(dr.isfinite(roughness), roughness, 0.0), 0.0, 1.0)
        return dr.maximum(roughness * roughness, MIN_GGX_ALPHA)

    @staticmethod
    def masking(alpha, wi, wo):
        """G1(wi) and G2(wi, wo) = 1 / (1 + Λ(wi) + Λ(wo))."""
        lambda_i = ggx_lambda(alpha, mi.Frame3f.cos_theta(wi))
        lambda_o = ggx_lambda(alpha, mi.Frame3f.cos_theta(wo))
        return 1.0 / (1.0 + lambda_i), 1.0 / (1.0 + lambda_i + lambda_o)

    def sample_rough(self, ctx, si, sample1, sample2, active):
        cos_i, front, active = self.incidence(si, active)
        alpha = self.alpha(si, active)
        distr = mi.MicrofacetDistribution(mi.MicrofacetType.GGX, alpha, True)
        m, pdf_m = distr.sample(dr.mulsign(si.wi, cos_i), sample2)
        active = active & (pdf_m > 0.0)
        dot_wi_m = dr.dot(si.wi, m)
        chosen = self.choose_lobe(ctx, si, dot_wi_m, front, active, sample1, glossy=True)
        if chosen is None:
            return dr.zeros(mi.BSDFSample3f), dr.zeros(mi.Spectrum)
        r, t, p_r, selected_r, cos_t, eta_ti, bs = chosen
        bs.wo = dr.select(selected_r, mi.reflect(si.wi, m), mi.refract(si.wi, m, cos_t, eta_ti))
        cos_o, dot_wo_m = mi.Frame3f.cos_theta(bs.wo), dr.dot(bs.wo, m)
        active = active & dr.select(selected_r, cos_o * cos_i > 0.0, cos_o * cos_i < 0.0)
        active = active & (dot_wo_m * cos_o > 0.0)
        p_lobe = dr.select(selected_r, p_r, 1.0 - p_r)
        bs.pdf = pdf_m * p_lobe * dr.abs(self.half_vector_jacobian(selected_r, dot_wi_m, dot_wo_m, bs.eta))
        active = active & (bs.pdf > 0.0)
        g1_i, g2 = self.masking(alpha, si.wi, bs.wo)
        value = dr.select(selected_r, r, t * self.radiance_scale(ctx, eta_ti))
        weight = value * (g2 / g1_i) / dr.maximum(p_lobe, 1e-30)
        return bs, dr.select(active, mi.Spectrum(weight), 0.0)

    @staticmethod
    def half_vector_jacobian(reflect, dot_wi_m, dot_wo_m, eta_it):
        """dω_m / dω_o for reflection, and for refraction with relative index eta_it."""
        return dr.select(
            reflect,
            1.0 / (4.0 * dot_wo_m),
            eta_it * eta_it * dot_wo_m / dr.square(dot_wi_m + eta_it * dot_wo_m),
        )

    def eval_pdf_rough(self, ctx, si, wo, active):
        flags = self._flags
        cos_i, cos_o = mi.Frame3f.cos_theta(si.wi), mi.Frame3f.cos_theta(wo)
        front = cos_i > 0.0
        reflect = cos_i * cos_o > 0.0
        has_r = ctx.is_enabled(flags.GlossyReflection, 0)
        has_t = self.transmissive and ctx.is_enabled(flags.GlossyTransmission, 1)
        active = active & (cos_i != 0.0) & ((has_r & reflect) | (has_t & _not(reflect)))
        if not self.transmissive:
            active = active & front
        eta_it = dr.select(front, self.eta, 1.0 / self.eta)
        m = dr.normalize(si.wi + wo * dr.select(reflect, 1.0, eta_it))
        m = dr.mulsign(m, mi.Frame3f.cos_theta(m))
        dot_wi_m, dot_wo_m = dr.dot(si.wi, m), dr.dot(wo, m)
        active = active & (dot_wi_m * cos_i > 0.0) & (dot_wo_m * cos_o > 0.0)
        r, t = self.film(si, dr.abs(dot_wi_m), front, active)
        p_r = self.lobe_choice(ctx, r, t, dr.abs(dot_wi_m), front, glossy=True)
        if p_r is None:
            return dr.zeros(mi.Spectrum), mi.Float(0.0)
        alpha = self.alpha(si, active)
        distr = mi.MicrofacetDistribution(mi.MicrofacetType.GGX, alpha, True)
        d = distr.eval(m)
        _, g2 = self.masking(alpha, si.wi, wo)
        value_r = r * (d * g2 / (4.0 * dr.abs(cos_i)))
        value_t = (
            t
            * self.radiance_scale(ctx, 1.0 / eta_it)
            * dr.abs(d * g2 * eta_it * eta_it * dot_wi_m * dot_wo_m / (cos_i * dr.square(dot_wi_m + eta_it * dot_wo_m)))
        )
        value = dr.select(reflect, value_r, value_t)
        jacobian = dr.abs(self.half_vector_jacobian(reflect, dot_wi_m, dot_wo_m, eta_it))
        pdf = distr.pdf(dr.mulsign(si.wi, cos_i), m) * dr.select(reflect, p_r, 1.0 - p_r) * jacobian
        return dr.select(active, mi.Spectrum(value), 0.0), dr.select(active, pdf, 0.0)


#: The pieces of the BSDF class beside Mitsuba's interface.
_PIECES = (_FilmLoading, _FilmLobes, _GgxLobes)


def _make_bsdf(symbolic):
    """The BSDF class of the variant set now: Mitsuba's interface (the
    methods its C++ side calls), with the methods of _PIECES (the film's
    state, its lobes, GGX) copied in: a nanobind type takes exactly one
    base, so they cannot be mixed in by inheritance."""

    class IridFilm(mi.BSDF):
        """irid's thin film: exact per-wavelength R and T, smooth or GGX-rough."""

        _flags = mi.BSDFFlags

        def __init__(self, props):
            mi.BSDF.__init__(self, props)
            self._load(props, symbolic)

        def traverse(self, callback):
            callback.put("thickness_nm", self.thickness, mi.ParamFlags.Differentiable)
            # A film loaded smooth has delta lobes, which no roughness value changes.
            changeable = mi.ParamFlags.Differentiable if self.rough else mi.ParamFlags.NonDifferentiable
            callback.put("roughness", self.roughness, changeable)

        def parameters_changed(self, keys=[]):
            if "roughness" in keys and not self.rough and not dr.all(self.roughness == 0.0, axis=None):
                raise FilmError(
                    "roughness",
                    "this film was loaded smooth (roughness 0: delta lobes); load it with a roughness "
                    "above 0 to change or optimize it",
                )
            for name in ("thickness", "roughness"):
                value = getattr(self, name)
                if isinstance(value, mi.Float) and dr.width(value) != 1:
                    raise FilmError(f"{name}_nm" if name == "thickness" else name, "must be one number (or a texture)")

        def sample(self, ctx, si, sample1, sample2, active=True):
            if self.rough:
                return self.sample_rough(ctx, si, sample1, sample2, active)
            return self.sample_smooth(ctx, si, sample1, active)

        def eval(self, ctx, si, wo, active=True):
            if not self.rough:
                return dr.zeros(mi.Spectrum)
            return self.eval_pdf_rough(ctx, si, wo, active)[0]

        def pdf(self, ctx, si, wo, active=True):
            if not self.rough:
                return mi.Float(0.0)
            return self.eval_pdf_rough(ctx, si, wo, active)[1]

        def eval_pdf(self, ctx, si, wo, active=True):
            if not self.rough:
                return dr.zeros(mi.Spectrum), mi.Float(0.0)
            return self.eval_pdf_rough(ctx, si, wo, active)

        def to_string(self):
            return self._description()

    for piece in _PIECES:
        for name, value in vars(piece).items():
            if not name.startswith("__"):
                setattr(IridFilm, name, value)
    return IridFilm
