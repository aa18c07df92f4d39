"""irid_film rendered by Mitsuba: pixels against irid's exact colours, the
furnace, the table path against the solver path."""

import numpy as np
import pytest

from mitsuba_setup import COATED_GLASS, FILM_ON_GOLD, JIT, SOAP, delta_e, irid, mi, orthographic_sphere, rgb_to_xyz, use

SIZE = 16
SUBPIXELS = 8


def expected_sphere_xyz(stack, size=SIZE, sub=SUBPIXELS, roughness=None):
    """The reflected colour each pixel of orthographic_sphere should show, and
    which pixels lie wholly within r < 0.9 of the sphere. With a roughness,
    the colour at each angle is the rough film's directional albedo:
    ``Stack.color(roughness=)``'s F_eff times its lobe_albedo (a lobe of
    colour F_eff has the film's albedo exactly, docs/rough.md).

    The angle at every point of the image is known in closed form: an
    orthographic ray through (x, y) of [-1, 1]² meets the unit sphere where
    the normal is (x, y, √(1 − x² − y²)), so cos θ = √(1 − r²). Each pixel
    is the mean over a sub × sub grid of such points of irid's colour at that
    angle (colours are linear, so the mean of colours is the colour of the
    mean spectrum); the box filter weighs a pixel's area evenly.
    """
    centres = (np.arange(size * sub) + 0.5) / (size * sub) * 2.0 - 1.0
    x, y = np.meshgrid(centres, centres)
    r2 = x * x + y * y
    hit = r2 < 1.0
    angles = np.degrees(np.arccos(np.sqrt(1.0 - r2[hit])))
    xyz = np.zeros(x.shape + (3,))
    if roughness is None:
        xyz[hit] = stack.color(angles)["reflectance_xyz"]
    else:
        rough = stack.color(angles, roughness=roughness)
        xyz[hit] = rough["reflectance_xyz"] * rough["lobe_albedo"][:, None]
    per_pixel = xyz.reshape(size, sub, size, sub, 3).mean(axis=(1, 3))
    inner = (r2 < 0.9**2).reshape(size, sub, size, sub).all(axis=(1, 3))
    return per_pixel, inner


def test_film_over_metal_pixels_are_irids_colours(jit):
    scene = orthographic_sphere(irid.mitsuba.bsdf(FILM_ON_GOLD, thickness_nm=300.0), SIZE)
    image = np.array(mi.render(scene, spp=256, seed=1))
    expected, inner = expected_sphere_xyz(FILM_ON_GOLD)
    de = delta_e(rgb_to_xyz(image[inner]), expected[inner])
    assert inner.sum() == 140
    # Measured 0.03 mean, 0.08 max at 256 spp (0.012 and 0.034 at 1024 spp).
    assert de.max() <= 0.5 and de.mean() <= 0.1, (de.mean(), de.max())


def test_a_thickness_texture_paints_the_film(jit):
    """A bitmap of thickness (raw values in nm) gives each pixel the colour
    of its own thickness: left half 250 nm, right half 420 nm."""
    bitmap = mi.Bitmap(np.array([[[250.0], [420.0]]], dtype=np.float32))
    texture = {"type": "bitmap", "bitmap": bitmap, "raw": True, "filter_type": "nearest"}
    scene = orthographic_sphere(irid.mitsuba.bsdf(FILM_ON_GOLD, thickness_nm=texture), SIZE)
    image = np.array(mi.render(scene, spp=256, seed=1))
    # The sphere's u is its azimuth / 2π: u < 0.5 (250 nm) for y > 0 in
    # object space, i.e. the upper rows of this view; the row between is mixed.
    expected = {}
    for thickness in (250.0, 420.0):
        expected[thickness], inner = expected_sphere_xyz(_with_thickness(FILM_ON_GOLD, thickness))
    rows = np.arange(SIZE)[:, None] * np.ones(SIZE)[None, :]
    for thickness, band in ((250.0, rows < SIZE // 2 - 1), (420.0, rows > SIZE // 2)):
        pixels = inner & band
        de = delta_e(rgb_to_xyz(image[pixels]), expected[thickness][pixels])
        assert pixels.sum() > 40 and de.max() <= 0.5, (thickness, de.max())


@pytest.mark.parametrize("roughness", [0.3, 0.6])
def test_rough_film_pixels_are_irids_rough_albedo(jit, roughness):
    """The rough lobe (GGX, the film's Fresnel per microfacet) against irid's
    own rough definition: under the constant emitter, one bounce off the
    convex sphere, each pixel is the film's directional albedo at its view
    angle, which irid computes by deterministic quadrature in
    ``Stack.color(roughness=)`` independently of Mitsuba's sampling.

    Measured at 1024 spp, seed 1: ΔE00 0.12 mean, 0.29 max at roughness 0.3
    (0.18, 0.53 at 0.6), the pixels' mean XYZ within 6e-4 of irid's
    (relative), a difference that falls as the noise does (0.41, 0.19, 0.09
    ΔE00 mean at 256, 1024, 4096 spp at 0.6). The smooth colour at the view
    angle misses by 1.3e-2 (0.3) and 0.19 (0.6)."""
    scene = orthographic_sphere(irid.mitsuba.bsdf(FILM_ON_GOLD, thickness_nm=300.0, roughness=roughness), SIZE)
    image = rgb_to_xyz(np.array(mi.render(scene, spp=1024, seed=1)))
    # Four by four points per pixel: the rough colour varies slowly with angle.
    expected, inner = expected_sphere_xyz(FILM_ON_GOLD, sub=4, roughness=roughness)
    smooth, _ = expected_sphere_xyz(FILM_ON_GOLD, sub=4)
    de = delta_e(image[inner], expected[inner])
    assert inner.sum() == 148
    assert de.max() <= 1.0 and de.mean() <= 0.3, (de.mean(), de.max())
    albedo_error = np.abs((image[inner] / expected[inner] - 1.0).mean(axis=0)).max()
    smooth_error = np.abs((image[inner] / smooth[inner] - 1.0).mean(axis=0)).max()
    assert albedo_error <= 2e-3, albedo_error
    assert smooth_error >= 5e-3, smooth_error


def _with_thickness(stack, thickness):
    layers = [(m, thickness if i == 0 else t) for i, (m, t) in enumerate(stack.layers)]
    return irid.Stack(ambient=stack.ambient, layers=layers, substrate=stack.substrate)


@pytest.mark.parametrize("stack", [SOAP, COATED_GLASS], ids=["soap-film", "coated-glass"])
def test_lossless_film_in_a_furnace_is_invisible(jit, stack):
    """A lossless film (free-standing, or on a lossless substrate: refraction,
    total internal reflection inside the sphere) neither absorbs nor emits:
    under the uniform constant emitter the sphere is the background.

    The noise is large for its size near white (a path that reflects carries
    R(λ) / mean R: the soap film's pixels are 1-4 ΔE00 off at 256 spp, about
    0.75 mean at 4096), so the test is a z-test: eight independent renders
    give each pixel's mean and standard error, and every pixel and channel
    must be within 4.5 standard errors of 1."""
    thickness = stack.layers[0][1]
    # Inside a sphere a ray meets every interface at the angle it entered
    # by, so no total internal reflection traps it: 16 interactions leave
    # less than 1e-9 of the light unfollowed (R ≤ 0.15 per interaction).
    scene = orthographic_sphere(irid.mitsuba.bsdf(stack, thickness_nm=thickness), 4, max_depth=16)
    images = np.array([mi.render(scene, spp=128, seed=seed) for seed in range(8)])
    mean = images.mean(axis=0)
    standard_error = images.std(axis=0, ddof=1) / np.sqrt(len(images))
    z = np.abs(mean - 1.0) / np.maximum(standard_error, 1e-4)
    assert z.max() <= 4.5, (z.max(), mean.reshape(-1, 3))
    assert np.abs(mean.mean(axis=(0, 1)) - 1.0).max() <= 3e-3, mean.mean(axis=(0, 1))


@pytest.fixture(scope="module")
def glass_table(tmp_path_factory):
    """A small spectral table of the coated glass over 360–830 nm."""
    lut = irid.bake(
        COATED_GLASS,
        thickness_nm=(150.0, 350.0),
        kind="spectral",
        wavelengths_nm=(360.0, 830.0),
        resolution=(41, 48, 95),
        validation_points=4000,
    )
    path = tmp_path_factory.mktemp("tables") / "coated-glass-spectral.exr"
    lut.save(path)
    return path


def _film_response(variant, stack, table, cos_theta, wavelengths, thickness, front):
    """(R, T) of a loaded irid_film at lanes of points, through its own
    response code."""
    use(variant)
    entry = irid.mitsuba.bsdf(stack, thickness_nm=200.0, table=table)
    film = mi.load_dict(entry)
    r, t = film.response(
        mi.Float(thickness), mi.Float(cos_theta), mi.UnpolarizedSpectrum(wavelengths), mi.Bool(front), mi.Bool(True)
    )
    return np.array(r), np.array(t)


def test_table_lookup_is_irids_sampler(jit, glass_table):
    rng = np.random.default_rng(3)
    n = 3000
    thickness = rng.uniform(140.0, 360.0, n)  # beyond the axis ends too: clamped
    cos_theta = rng.uniform(0.0, 1.0, n)
    wavelengths = rng.uniform(360.0, 830.0, (4, n))
    r, t = _film_response(JIT, COATED_GLASS, str(glass_table), cos_theta, wavelengths, thickness, np.ones(n, bool))
    lut = irid.Lut.load(glass_table)
    r_ref, t_ref = lut.sample(thickness[None, :], cos_theta[None, :], wavelengths)
    np.testing.assert_allclose(r, r_ref, atol=2e-6)
    np.testing.assert_allclose(t, t_ref, atol=2e-6)


@pytest.mark.parametrize("front", [True, False], ids=["from-ambient", "from-substrate"])
def test_table_path_agrees_with_solver_path(jit, glass_table, front):
    """Both sides: from the substrate the table serves by reciprocity
    (T at the corresponding ambient angle, R = 1 − T, total internal
    reflection past the critical angle)."""
    rng = np.random.default_rng(4)
    n = 3000
    thickness = rng.uniform(150.0, 350.0, n)
    cos_theta = rng.uniform(0.02, 1.0, n)
    wavelengths = rng.uniform(360.0, 830.0, (4, n))
    sides = np.full(n, front)
    table = _film_response(JIT, COATED_GLASS, str(glass_table), cos_theta, wavelengths, thickness, sides)
    solver = _film_response(JIT, COATED_GLASS, None, cos_theta, wavelengths, thickness, sides)
    bound = max(irid.Lut.load(glass_table).header["error"]["validation"]["max_abs"]) + 1e-5
    for a, b in zip(table, solver):
        # The ambient-side cos θ axis stops at cos 89°: from the substrate,
        # points mapped below it are clamped, so compare within the axis.
        if not front:
            sin2 = (1 - cos_theta**2) * 1.5**2
            keep = (sin2 >= 1.0) | (np.sqrt(np.clip(1 - sin2, 0, 1)) >= np.cos(np.radians(89.0)))
            a, b = a[:, keep], b[:, keep]
        assert np.abs(a - b).max() <= bound, (np.abs(a - b).max(), bound)


@pytest.fixture(scope="module")
def glass_atlas(tmp_path_factory):
    """The coated glass's spectral table on the atlas (format version 4),
    over every angle."""
    lut = irid.bake(
        COATED_GLASS,
        thickness_nm=(150.0, 350.0),
        kind="spectral",
        wavelengths_nm=(360.0, 830.0),
        cos_theta=(0.0, 1.0),
        max_error=5e-3,
        validation_points=4000,
    )
    path = tmp_path_factory.mktemp("tables") / "coated-glass-atlas.exr"
    lut.save(path)
    return path


def test_atlas_table_is_irids_sampler_and_meets_the_solver(jit, glass_atlas):
    """An atlas table looked up in Dr.Jit is irid's own sampler (both in
    float32; Dr.Jit's log and square root may differ from Rust's in the last
    bit, which a texel's slope turns into a few 1e-6) and is within its
    target of the solver above its aliased strip."""
    lut = irid.Lut.load(glass_atlas)
    floor = lut.header["atlas"]["aliased_below_cos"]
    rng = np.random.default_rng(6)
    n = 3000
    thickness = rng.uniform(150.0, 350.0, n)
    cos_theta = rng.uniform(floor, 1.0, n)
    wavelengths = rng.uniform(360.0, 830.0, (4, n))
    front = np.ones(n, bool)
    r, t = _film_response(JIT, COATED_GLASS, str(glass_atlas), cos_theta, wavelengths, thickness, front)
    r_ref, t_ref = lut.sample(thickness[None, :], cos_theta[None, :], wavelengths)
    np.testing.assert_allclose(r, r_ref, atol=5e-6)
    np.testing.assert_allclose(t, t_ref, atol=5e-6)
    solver = _film_response(JIT, COATED_GLASS, None, cos_theta, wavelengths, thickness, front)
    assert np.abs(r - solver[0]).max() <= 5e-3 and np.abs(t - solver[1]).max() <= 5e-3


def test_table_render_matches_solver_render(glass_table):
    """The same scene, sampler and seed with a table (symbolic Dr.Jit) and
    with the solver (evaluated): the images differ by the table's error only."""
    images = []
    for table, symbolic in ((str(glass_table), True), (None, False)):
        use(JIT, symbolic=symbolic)
        scene = orthographic_sphere(irid.mitsuba.bsdf(COATED_GLASS, thickness_nm=250.0, table=table), 8, max_depth=8)
        images.append(np.array(mi.render(scene, spp=64, seed=5)))
    use(JIT)
    de = delta_e(rgb_to_xyz(images[0].reshape(-1, 3)), rgb_to_xyz(images[1].reshape(-1, 3)))
    assert de.max() <= 0.5, de.max()


def test_a_solver_film_traced_symbolically_warns_and_gives_zeros(glass_table):
    """Dr.Jit's symbolic calls trace every live BSDF, also those of other
    scenes: a film without a table, alive while a table scene renders in
    symbolic mode, must not change or break that render (it logs a warning
    once and gives zeros where it is traced)."""
    use(JIT, symbolic=True)
    scene = orthographic_sphere(irid.mitsuba.bsdf(COATED_GLASS, thickness_nm=250.0, table=str(glass_table)), 8)
    alone = np.array(mi.render(scene, spp=16, seed=5))
    use(JIT)
    stale = mi.load_dict(irid.mitsuba.bsdf(COATED_GLASS, thickness_nm=250.0, roughness=0.3))
    use(JIT, symbolic=True)
    beside = np.array(mi.render(scene, spp=16, seed=5))
    use(JIT)
    assert "solver" in str(stale)
    np.testing.assert_array_equal(beside, alone)
