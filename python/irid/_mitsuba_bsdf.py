"""The Dr.Jit side of ``irid_film`` (irid.mitsuba makes the class once a
Mitsuba variant is set): the film's R and T per wavelength, from irid's
solver through numpy or from a spectral table looked up in Dr.Jit, and the
BSDF's sampling, evaluation and density."""

import drjit as dr
import mitsuba as mi
import numpy as np

from .mitsuba import MAX_THICKNESS_NM, SPECTRAL_RANGE_NM, FilmError, _FilmSetup, ggx_lambda

#: The smallest α of Mitsuba's MicrofacetDistribution (it clamps below).
MIN_GGX_ALPHA = 1e-4

_SYMBOLIC = (
    "irid_film: a film without a table, or with an atlas table, was traced in a symbolic Dr.Jit loop or call, where its solver "
    "cannot run (it runs between kernels); it gives zeros there. Render in the thread that called "
    "irid.mitsuba.register() (which turns symbolic loops and calls off), or give the film a grid table. "
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


class _SolverResponse:
    """R and T from irid's solver: the lanes' values go to numpy, one call
    per side of the film, and come back as a spectrum."""

    def __init__(self, setup):
        self.stack, self.layer = setup.stack, setup.layer
        self.jit = dr.is_jit_v(mi.Float)
        self.warned = False

    def __call__(self, thickness, cos_theta, wavelengths, front, active):
        if self.jit and dr.flag(dr.JitFlag.SymbolicScope):
            if not self.warned:
                mi.Log(mi.LogLevel.Warn, _SYMBOLIC)
                self.warned = True
            return dr.zeros(mi.UnpolarizedSpectrum), dr.zeros(mi.UnpolarizedSpectrum)
        thickness, cos_theta, wavelengths, front = _sanitized(thickness, cos_theta, wavelengths, front, active)
        w = np.asarray(wavelengths, dtype=np.float64)
        c, d, f, a = (
            np.broadcast_to(np.asarray(x, dtype=t), w.shape)
            for x, t in ((cos_theta, np.float64), (thickness, np.float64), (front, bool), (active, bool))
        )
        r, t = np.zeros(w.shape), np.zeros(w.shape)
        # Only the lanes that ask: a wavefront holds every path, finished or not.
        for side, lanes in (("ambient", f & a), ("substrate", ~f & a)):
            if lanes.any():
                r[lanes], t[lanes] = self.stack.response(c[lanes], w[lanes], d[lanes], layer=self.layer, side=side)
        return mi.UnpolarizedSpectrum(r.astype(np.float32)), mi.UnpolarizedSpectrum(t.astype(np.float32))


class _TableResponse:
    """R and T from a spectral table, interpolated as irid's sampler does
    (linear in each axis value, clamped at the ends): for a grid table a
    binary search per non-uniform axis and eight gathers per wavelength in
    Dr.Jit; for an atlas table (format version 4) and in the scalar
    variant, irid's own sampler (an atlas's lanes go to numpy and back
    between kernels, as the solver's do). Light from a lossless substrate
    through lossless layers is served by reciprocity: T is the same at the
    corresponding angle in the ambient, and R = 1 − T (total internal
    reflection where no such angle exists)."""

    def __init__(self, setup):
        self.lut = setup.table
        axes = self.lut.header["axes"]
        self.sizes = [len(a["nodes"]) for a in axes]  # thickness, cos θ, wavelength
        self.ends = [(a["nodes"][0], a["nodes"][-1]) for a in axes]
        self.jit = dr.is_jit_v(mi.Float)
        self.atlas = "atlas" in self.lut.header
        self.warned = False
        self.eta_per_nm = setup.eta_per_nm
        if self.jit:
            # The substrate side's angle needs η on every path, the
            # atlas's sampled one too.
            self.eta_nodes = mi.Float(self.eta_per_nm)
        if self.jit and not self.atlas:
            self.nodes = [mi.Float(np.asarray(a["nodes"], dtype=np.float32)) for a in axes]
            data = self.lut.data
            self.reflectance = mi.Float(np.ascontiguousarray(data[..., 0]).ravel())
            self.transmittance = mi.Float(np.ascontiguousarray(data[..., 1]).ravel())

    def _eta(self, wavelength):
        """n_substrate / n_ambient at ``wavelength`` (1 nm nodes, linear)."""
        x = dr.clip(wavelength - SPECTRAL_RANGE_NM[0], 0.0, len(self.eta_per_nm) - 1.0)
        if not self.jit:
            return float(np.interp(x, np.arange(len(self.eta_per_nm)), self.eta_per_nm))
        i = mi.UInt32(dr.minimum(dr.floor(x), len(self.eta_per_nm) - 2.0))
        f = x - mi.Float(i)
        return dr.lerp(dr.gather(mi.Float, self.eta_nodes, i), dr.gather(mi.Float, self.eta_nodes, i + 1), f)

    def _locate(self, axis, x):
        """The interval of ``axis`` holding ``x`` (clamped) and the weight of its upper node."""
        lo, hi = self.ends[axis]
        if self.sizes[axis] == 1:
            return mi.UInt32(0), mi.Float(0.0)
        x = dr.clip(x, lo, hi)
        nodes = self.nodes[axis]
        i = dr.binary_search(0, self.sizes[axis] - 2, lambda j: dr.gather(mi.Float, nodes, j + 1) < x)
        x0, x1 = dr.gather(mi.Float, nodes, i), dr.gather(mi.Float, nodes, i + 1)
        return i, dr.clip((x - x0) / (x1 - x0), 0.0, 1.0)

    def _lookup(self, thickness, cos_theta, wavelength):
        (ti, tf), (ci, cf) = self._locate(0, thickness), self._locate(1, cos_theta)
        wi, wf = self._locate(2, wavelength)
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

    def _sampled(self, thickness, cos_theta, wavelength):
        """irid's sampler on a wavefront's lanes, through numpy."""
        coordinates = (np.asarray(x, dtype=np.float64) for x in (thickness, cos_theta, wavelength))
        return (mi.Float(np.asarray(v, dtype=np.float32)) for v in self.lut.sample(*coordinates))

    def __call__(self, thickness, cos_theta, wavelengths, front, active):
        if self.jit and self.atlas and dr.flag(dr.JitFlag.SymbolicScope):
            if not self.warned:
                mi.Log(mi.LogLevel.Warn, _SYMBOLIC)
                self.warned = True
            return dr.zeros(mi.UnpolarizedSpectrum), dr.zeros(mi.UnpolarizedSpectrum)
        thickness, cos_theta, wavelengths, front = _sanitized(thickness, cos_theta, wavelengths, front, active)
        r, t = [], []
        for k in range(len(wavelengths)):
            # From the substrate: the angle in the ambient with the same
            # tangential index (none past the critical angle).
            eta = self._eta(wavelengths[k])
            sin2_ambient = (1.0 - cos_theta * cos_theta) * eta * eta
            cos_ambient = dr.select(front, cos_theta, dr.safe_sqrt(1.0 - sin2_ambient))
            if self.jit and self.atlas:
                r_k, t_k = self._sampled(thickness, cos_ambient, wavelengths[k])
            elif self.jit:
                r_k, t_k = self._lookup(thickness, cos_ambient, wavelengths[k])
            else:
                r_k, t_k = (float(v) for v in self.lut.sample(thickness, cos_ambient, wavelengths[k]))
            t_k = dr.select(front | (sin2_ambient < 1.0), t_k, 0.0)
            r.append(dr.select(front, r_k, 1.0 - t_k))
            t.append(t_k)
        return mi.UnpolarizedSpectrum(*r), mi.UnpolarizedSpectrum(*t)


def _make_bsdf(symbolic):
    flags = mi.BSDFFlags

    class IridFilm(mi.BSDF):
        """irid's thin film: exact per-wavelength R and T, smooth or GGX-rough."""

        def __init__(self, props):
            mi.BSDF.__init__(self, props)
            values = {key: props[key] for key in props.keys()}
            values["type"] = "irid_film"
            setup = _FilmSetup.from_values(values)
            self.setup = setup
            self.thickness = setup.thickness
            self.textured = isinstance(setup.thickness, mi.Texture)
            if not self.textured and not isinstance(setup.thickness, float):
                raise FilmError("thickness_nm", f"expected a number or a texture, got {type(setup.thickness).__name__}")
            self.transmissive = setup.transmissive
            self.eta = setup.eta
            # Mitsuba's GGX takes no α below 1e-4 (roughness 0.01); the
            # masking uses the same α, so the lobe is one GGX throughout.
            self.alpha = max(setup.alpha, MIN_GGX_ALPHA) if setup.alpha > 0.0 else 0.0
            self.rough = setup.alpha > 0.0
            between_kernels = setup.table is None or "atlas" in setup.table.header
            if between_kernels and dr.is_jit_v(mi.Float) and symbolic:
                raise FilmError(
                    "table",
                    ("missing" if setup.table is None else "an atlas table (format version 4, read by irid's sampler)")
                    + ": irid.mitsuba.register(symbolic=True) keeps Dr.Jit's symbolic loops, in which "
                    "only a grid table can be looked up (the solver and irid's sampler run between kernels); "
                    "give a grid table (irid bake --layout grid) or register without symbolic=True",
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
            if self.textured:
                self.m_flags = self.m_flags | flags.SpatiallyVarying

        # -- the film ---------------------------------------------------------

        def film(self, si, cos_theta, front, active):
            """The film's (R, T) at ``cos_theta`` for light from the front
            (ambient) or back (substrate) side, per wavelength of ``si``."""
            if self.textured:
                thickness = self.thickness.eval_1(si, active)
            else:
                thickness = mi.Float(self.thickness)
            return self.response(thickness, cos_theta, si.wavelengths, front, active)

        def lobe_choice(self, ctx, r, t, cos_in, front, glossy):
            """The probability of sampling reflection rather than transmission
            (the spectrum's mean R against its mean T), or None when neither
            lobe is enabled."""
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

        @staticmethod
        def lobe_sample(selected_r, eta_it, glossy):
            """A BSDFSample3f naming the lobe chosen (reflection or refraction)."""
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

        # -- smooth -----------------------------------------------------------

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

        # -- rough (GGX, alpha = roughness², height-correlated Smith G2) ------

        def masking(self, wi, wo):
            """G1(wi) and G2(wi, wo) = 1 / (1 + Λ(wi) + Λ(wo))."""
            lambda_i = ggx_lambda(self.alpha, mi.Frame3f.cos_theta(wi))
            lambda_o = ggx_lambda(self.alpha, mi.Frame3f.cos_theta(wo))
            return 1.0 / (1.0 + lambda_i), 1.0 / (1.0 + lambda_i + lambda_o)

        def sample_rough(self, ctx, si, sample1, sample2, active):
            cos_i, front, active = self.incidence(si, active)
            distr = mi.MicrofacetDistribution(mi.MicrofacetType.GGX, self.alpha, True)
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
            g1_i, g2 = self.masking(si.wi, bs.wo)
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
            distr = mi.MicrofacetDistribution(mi.MicrofacetType.GGX, self.alpha, True)
            d = distr.eval(m)
            _, g2 = self.masking(si.wi, wo)
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

        # -- Mitsuba's interface ------------------------------------------------

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
            s = self.setup
            source = "table" if s.table is not None else "solver"
            return (
                f"IridFilm[layer={s.layer}, thickness_nm={s.thickness}, roughness={s.roughness}, "
                f"{source}, {'transmissive' if self.transmissive else 'opaque'}]"
            )

    return IridFilm
