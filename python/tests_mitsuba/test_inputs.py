"""The natural steps off the documented path (issue 39): a roughness given as
a texture, an irid.Stack object as ``stack``."""

import numpy as np
import pytest

from mitsuba_setup import COATED_GLASS, FILM_ON_GOLD, dr, irid, mi, orthographic_sphere

WAVELENGTHS = [420.0, 515.0, 600.0, 700.0]


def _surface(n, u, theta_deg=35.0):
    si = dr.zeros(mi.SurfaceInteraction3f, n)
    theta = np.radians(theta_deg)
    si.wi = mi.Vector3f(float(np.sin(theta)), 0.0, float(np.cos(theta)))
    si.uv = mi.Point2f(u, 0.5)
    si.wavelengths = mi.UnpolarizedSpectrum(WAVELENGTHS)
    return si


def _sampled(bsdf, si, n, seed=2):
    u = np.random.default_rng(seed).random((3, n)).astype(np.float32)
    bs, weight = bsdf.sample(mi.BSDFContext(), si, mi.Float(u[0]), mi.Point2f(u[1], u[2]))
    value, pdf = bsdf.eval_pdf(mi.BSDFContext(), si, bs.wo)
    return np.concatenate([np.array(bs.wo), np.array(weight), np.array(value), np.array(pdf)[None]])


@pytest.mark.parametrize("stack", [FILM_ON_GOLD, COATED_GLASS], ids=["film-on-gold", "coated-glass"])
def test_a_textured_roughness_is_the_roughness_at_each_point(jit, stack):
    """A bitmap of two roughness values (0.2 left, 0.5 right, nearest): at
    each half the film samples, evaluates and weighs exactly as a film of
    that one roughness."""
    texture = {"type": "bitmap", "raw": True, "filter_type": "nearest", "data": mi.TensorXf(np.array([[[0.2], [0.5]]], np.float32))}
    painted = mi.load_dict(irid.mitsuba.bsdf(stack, thickness_nm=260.0, roughness=texture))
    n = 2000
    for u, roughness in ((0.25, 0.2), (0.75, 0.5)):
        plain = mi.load_dict(irid.mitsuba.bsdf(stack, thickness_nm=260.0, roughness=roughness))
        np.testing.assert_allclose(_sampled(painted, _surface(n, u), n), _sampled(plain, _surface(n, u), n), rtol=1e-6, atol=1e-7)
    other = mi.load_dict(irid.mitsuba.bsdf(stack, thickness_nm=260.0, roughness=0.2))
    assert np.abs(_sampled(painted, _surface(n, 0.75), n) - _sampled(other, _surface(n, 0.75), n)).max() > 1e-2


def test_the_issues_checkerboard_roughness_renders(jit):
    """As filed: a checkerboard roughness, written as a plain scene dict."""
    entry = {"type": "irid_film", "stack": COATED_GLASS.to_json(), "thickness_nm": 260.0, "roughness": {"type": "checkerboard"}}
    bsdf = mi.load_dict(entry)
    assert "roughness=texture" in str(bsdf)
    image = np.array(mi.render(orthographic_sphere(entry, 8), spp=16, seed=1))
    assert np.isfinite(image).all() and image.mean() > 0.05


def test_a_textured_roughness_on_a_free_standing_film_is_refused(jit):
    """Refused as a rough number is (a texture may be rough anywhere)."""
    soap = irid.Stack(ambient=1.0, layers=[(1.33, 500.0)], substrate=1.0)
    with pytest.raises(irid.mitsuba.FilmError, match="^irid_film: roughness: a rough film with the same index"):
        irid.mitsuba.bsdf(soap, thickness_nm=500.0, roughness={"type": "checkerboard"})


def test_a_bad_roughness_object_is_named_not_dumped(jit):
    with pytest.raises(irid.mitsuba.FilmError) as caught:
        irid.mitsuba.bsdf(FILM_ON_GOLD, thickness_nm=300.0, roughness=[0.1] * 1000)
    assert str(caught.value) == "irid_film: roughness: must be a number in [0, 1] or a texture, got list"


def test_an_irid_stack_object_is_accepted_as_stack(jit):
    """mi.load_dict with an irid.Stack (nanobind cannot hold it): the film is
    the one its JSON gives, at the top level and inside a scene."""
    entry = {"type": "irid_film", "stack": COATED_GLASS, "thickness_nm": 250.0, "roughness": 0.3}
    as_object = mi.load_dict(entry)
    as_json = mi.load_dict(dict(entry, stack=COATED_GLASS.to_json()))
    si = _surface(500, 0.5)
    np.testing.assert_array_equal(_sampled(as_object, si, 500), _sampled(as_json, si, 500))
    scene = orthographic_sphere(entry, 4)
    assert np.isfinite(np.array(mi.render(scene, spp=4))).all()
    # The caller's dict is left as it was.
    assert entry["stack"] is COATED_GLASS
