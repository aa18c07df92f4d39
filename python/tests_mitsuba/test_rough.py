"""irid_film's rough lobe against irid's own rough definition (docs/rough.md):
its directional albedo, estimated from the BSDF's own samples and integrated
to colour, is ``Stack.color(roughness=)``'s F_eff times lobe_albedo (irid's
deterministic quadrature, no Mitsuba involved); roughness 0 is the smooth
BSDF and small roughness tends to it; bad roughness is one line at load_dict
time."""

import numpy as np
import pytest

from mitsuba_setup import COATED_GLASS, FILM_ON_GOLD, SOAP, colour, delta_e, dr, irid, mi
from test_render import glass_table  # noqa: F401 (a fixture)

#: Mitsuba's spectral range at 1 nm, as irid integrates colour (docs/color.md).
WAVELENGTHS = np.arange(360.0, 831.0)
#: A ray carries four wavelengths; the last group repeats 830 nm, dropped.
GROUPS = (len(WAVELENGTHS) + 3) // 4


def _d65_xyz_weights():
    """XYZ = R(λ) · weights: CIE 1931 2° and D65 from colour-science (an
    implementation independent of irid's), Y = 1 for a perfect reflector."""
    shape = colour.SpectralShape(WAVELENGTHS[0], WAVELENGTHS[-1], 1)
    cmfs = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"].copy().align(shape).values
    d65 = colour.SDS_ILLUMINANTS["D65"].copy().align(shape).values
    return cmfs * d65[:, None] / (d65 * cmfs[:, 1]).sum()


XYZ_WEIGHTS = _d65_xyz_weights()


def _reflection_context(reflection_only):
    ctx = mi.BSDFContext()
    if reflection_only:
        ctx.type_mask = +mi.BSDFFlags.GlossyReflection
    return ctx


def sampled_albedo_xyz(bsdf, theta_deg, n, seed, reflection_only=False, transmitted=False, stratified_choice=False):
    """The directional albedo of ``bsdf``'s reflection (or transmission) at
    ``theta_deg`` in a uniform white environment (D65 at luminance 1), as
    XYZ: the mean of n samples' reflected (transmitted) weights, each sample
    taken at all 471 wavelengths (the same random numbers for every group of
    four). ``stratified_choice``: the lobe-choosing numbers are (i + ½)/n,
    not random. Returns the mean and its standard error per channel."""
    wavelengths = np.concatenate([WAVELENGTHS, np.full(4 * GROUPS - len(WAVELENGTHS), WAVELENGTHS[-1])])
    u = np.random.default_rng(seed).random((3, n)).astype(np.float32)
    if stratified_choice:
        u[0] = (np.arange(n, dtype=np.float32) + 0.5) / n
    u = np.repeat(u, GROUPS, axis=1)
    si = dr.zeros(mi.SurfaceInteraction3f, n * GROUPS)
    theta = np.radians(theta_deg)
    si.wi = mi.Vector3f(float(np.sin(theta)), 0.0, float(np.cos(theta)))
    si.wavelengths = mi.UnpolarizedSpectrum(np.tile(wavelengths.reshape(GROUPS, 4).T, (1, n)).astype(np.float32))
    ctx = _reflection_context(reflection_only)
    bs, weight = bsdf.sample(ctx, si, mi.Float(u[0]), mi.Point2f(u[1], u[2]))
    same_side = np.array(mi.Frame3f.cos_theta(bs.wo)) * np.cos(theta) > 0.0
    spectra = (np.array(weight) * (~same_side if transmitted else same_side)).T.reshape(n, 4 * GROUPS)[:, : len(WAVELENGTHS)]
    xyz = spectra @ XYZ_WEIGHTS
    return xyz.mean(axis=0), xyz.std(axis=0) / np.sqrt(n)


def irids_rough_albedo_xyz(stack, theta_deg, roughness):
    rough = stack.color([theta_deg], roughness=roughness)
    return rough["reflectance_xyz"][0] * rough["lobe_albedo"][0]


def test_the_colour_integration_is_irids():
    """The XYZ weights above turn the smooth film's spectrum (Stack.response)
    into Stack.color's colour: the comparison below is of lobes, not of
    colour pipelines."""
    cos_theta = np.full(WAVELENGTHS.shape, np.cos(np.radians(40.0)))
    for stack in (FILM_ON_GOLD, COATED_GLASS):
        r, _ = stack.response(cos_theta, WAVELENGTHS, stack.layers[0][1])
        np.testing.assert_allclose(r @ XYZ_WEIGHTS, stack.color([40.0])["reflectance_xyz"][0], atol=2e-7)


#: Cases a render of a sphere does not reach (test_render.py renders the film
#: on gold at roughness 0.3 and 0.6, views up to 64°): near-smooth, grazing,
#: roughness 1, a transmissive film, and (below) a table.
#: (name, stack, roughness, view angle, reflection only), the stacks at
#: their own thickness (300 and 250 nm). The film on gold reflects only; on
#: the coated glass a sample picks refraction with probability mean T /
#: (mean R + mean T), most of the time (R is a few per cent), so its reflection is
#: estimated with refraction turned off in the context (the lobe choice itself
#: is held by the chi² test in test_bsdf.py).
ALBEDO_CASES = [
    ("film-on-gold", FILM_ON_GOLD, 0.05, 0.0, False),
    ("film-on-gold", FILM_ON_GOLD, 0.6, 75.0, False),
    ("film-on-gold", FILM_ON_GOLD, 1.0, 60.0, False),
    ("coated-glass", COATED_GLASS, 0.3, 0.0, True),
    ("coated-glass", COATED_GLASS, 0.6, 60.0, True),
]
SAMPLES = 4096


@pytest.mark.parametrize(
    "name, stack, roughness, theta, reflection_only",
    ALBEDO_CASES,
    ids=[f"{c[0]} r={c[2]} θ={c[3]}" for c in ALBEDO_CASES],
)
def test_rough_albedo_is_irids_rough_colour(jit, name, stack, roughness, theta, reflection_only):
    """The lobe's directional albedo in a white environment, integrated to
    colour, is irid's F_eff × lobe_albedo within the estimate's noise (2e-4
    relative allowed beyond it: float32 directions and values, which is what
    is left at roughness 0.05, where the noise is 1e-6)."""
    bsdf = mi.load_dict(irid.mitsuba.bsdf(stack, thickness_nm=stack.layers[0][1], roughness=roughness))
    # At roughness 1 the weights G2/G1 spread most: four times the samples.
    samples = SAMPLES * (4 if roughness == 1.0 else 1)
    mean, error = sampled_albedo_xyz(bsdf, theta, samples, seed=int(theta) + int(100 * roughness), reflection_only=reflection_only)
    expected = irids_rough_albedo_xyz(stack, theta, roughness)
    _check_albedo(mean, error, expected, 2e-4 * expected)


def _check_albedo(mean, error, expected, allowance):
    """Every XYZ channel within 4.5 standard errors of the estimate plus
    ``allowance``; ΔE00 ≤ 0.5 (one standard error of 4096 samples at
    roughness 1 is 1.3 % relative, ΔE00 0.3). Prints the figures docs/mitsuba.md quotes
    (pytest -s)."""
    de = delta_e(mean, expected)
    print(f" ΔE00 {de:.3f}, XYZ off by {np.array2string((mean - expected) / expected, precision=5)} relative,"
          f" {np.array2string((mean - expected) / error, precision=2)} standard errors", end="")
    assert np.all(np.abs(mean - expected) <= 4.5 * error + allowance), ((mean - expected) / error, mean, expected)
    assert de <= 0.5, de


def test_rough_albedo_from_a_table_is_irids_rough_colour(jit, glass_table):
    """The same with the film looked up in a spectral table (Dr.Jit's
    trilinear lookup per microfacet angle) instead of solved: within the
    noise plus the table's own validation error."""
    table_error = max(irid.Lut.load(glass_table).header["error"]["validation"]["max_abs"])
    bsdf = mi.load_dict(irid.mitsuba.bsdf(COATED_GLASS, thickness_nm=250.0, roughness=0.4, table=str(glass_table)))
    mean, error = sampled_albedo_xyz(bsdf, 30.0, SAMPLES, seed=7, reflection_only=True)
    expected = irids_rough_albedo_xyz(COATED_GLASS, 30.0, 0.4)
    _check_albedo(mean, error, expected, table_error)


def _smooth_colour_xyz(stack, theta_deg):
    return stack.color([theta_deg])["reflectance_xyz"][0]


@pytest.mark.parametrize("roughness", [0.0, 0.01, 0.005])
def test_small_roughness_tends_to_the_smooth_film(jit, roughness):
    """Roughness 0 is the smooth BSDF itself: delta lobes, the very samples
    and weights of a film given no roughness. Roughness 0.01 (α = 1e-4,
    Mitsuba's smallest GGX α) and below is a lobe whose albedo is the smooth
    film's colour at the view angle (within 1e-4 relative)."""
    theta = 35.0
    bsdf = mi.load_dict(irid.mitsuba.bsdf(FILM_ON_GOLD, thickness_nm=300.0, roughness=roughness))
    if roughness == 0.0:
        smooth = mi.load_dict(irid.mitsuba.bsdf(FILM_ON_GOLD, thickness_nm=300.0))
        assert bsdf.flags() == smooth.flags() and bsdf.flags() & mi.BSDFFlags.DeltaReflection
        samples = []
        for film in (bsdf, smooth):
            si = dr.zeros(mi.SurfaceInteraction3f, 3)
            si.wi = mi.Vector3f(float(np.sin(np.radians(theta))), 0.0, float(np.cos(np.radians(theta))))
            si.wavelengths = mi.UnpolarizedSpectrum([420.0, 515.0, 600.0, 700.0])
            bs, weight = film.sample(mi.BSDFContext(), si, mi.Float([0.1, 0.5, 0.9]), mi.Point2f(0.3, 0.7))
            samples.append(np.concatenate([np.ravel(bs.wo), np.ravel(weight), np.ravel(bs.pdf)]))
        np.testing.assert_array_equal(samples[0], samples[1])
        return
    assert bsdf.flags() & mi.BSDFFlags.GlossyReflection
    mean, _ = sampled_albedo_xyz(bsdf, theta, 256, seed=3)
    np.testing.assert_allclose(mean, _smooth_colour_xyz(FILM_ON_GOLD, theta), rtol=1e-4)


@pytest.mark.parametrize("theta", [30.0, 150.0], ids=["from the air", "from the glass"])
def test_small_roughness_transmits_as_the_smooth_film(jit, theta):
    """The rough refraction lobe tends to the smooth film's refraction: at
    roughness 0.01 the light reflected and transmitted by the coated glass,
    lobe choice included (the same stratified choices for both films), is
    the smooth film's within 1e-5 relative (measured: 3e-8), from either
    side (radiance: T / η² from the air, T η² from the glass)."""
    films = [mi.load_dict(irid.mitsuba.bsdf(COATED_GLASS, thickness_nm=250.0, roughness=r)) for r in (0.01, 0.0)]
    for transmitted in (False, True):
        rough, smooth = (sampled_albedo_xyz(f, theta, 256, 5, transmitted=transmitted, stratified_choice=True)[0] for f in films)
        np.testing.assert_allclose(rough, smooth, rtol=1e-5)


BAD_ROUGHNESS = [float("nan"), -0.1, 1.5, float("inf"), -float("inf"), "0.3", True]


@pytest.mark.parametrize("roughness", BAD_ROUGHNESS, ids=[repr(r) for r in BAD_ROUGHNESS])
def test_bad_roughness_is_one_line_at_load_time(jit, roughness):
    """Through mi.load_dict (Mitsuba wraps the plugin's error in a
    RuntimeError whose last line is the plugin's), and through
    irid.mitsuba.bsdf(), which checks the dict it writes."""
    entry = {"type": "irid_film", "stack": FILM_ON_GOLD.to_json(), "thickness_nm": 300.0, "roughness": roughness}
    message = f"irid_film: roughness: must be a number in [0, 1] or a texture, got {roughness!r}"
    with pytest.raises(RuntimeError) as caught:
        mi.load_dict(entry)
    assert str(caught.value).strip().splitlines()[-1].endswith(message), str(caught.value)
    with pytest.raises(irid.mitsuba.FilmError) as caught:
        irid.mitsuba.bsdf(FILM_ON_GOLD, thickness_nm=300.0, roughness=roughness)
    assert str(caught.value) == message


def test_a_rough_free_standing_film_is_refused(jit):
    """A lossless film with the ambient's index behind it transmits straight
    through, which no microfacet lobe describes: refused when the dict is
    made and when it is loaded, smooth films of it accepted."""
    message = "irid_film: roughness: a rough film with the same index on both sides refracts nothing"
    with pytest.raises(irid.mitsuba.FilmError, match="^" + message):
        irid.mitsuba.bsdf(SOAP, thickness_nm=300.0, roughness=0.3)
    entry = {"type": "irid_film", "stack": SOAP.to_json(), "thickness_nm": 300.0, "roughness": 0.3}
    with pytest.raises(RuntimeError) as caught:
        mi.load_dict(entry)
    assert message in str(caught.value).strip().splitlines()[-1], str(caught.value)
    assert "IridFilm[" in str(mi.load_dict(dict(entry, roughness=0.0)))
