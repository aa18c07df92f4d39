"""Stack.response (R and T at arrays of points, each its own wavelength, from
either side) against Stack.solve and the reversed stack; Stack.to_json and
from_json."""

import numpy as np
import pytest

import irid

COATED = irid.Stack(ambient=1.0, layers=[("MgF2", 250.0), ((2.1, 0.02), 60.0)], substrate=1.52)


def test_response_is_solve_at_each_point():
    rng = np.random.default_rng(1)
    n = 400
    wavelengths = rng.uniform(360.0, 830.0, n)
    angles = rng.uniform(0.0, 89.0, n)
    thickness = rng.uniform(0.0, 600.0, n)
    r, t = COATED.response(np.cos(np.radians(angles)), wavelengths, thickness, layer=1)
    for i in range(0, n, 37):
        one = COATED.solve([wavelengths[i]], [angles[i]], thickness_nm=[thickness[i]], layer=1)
        assert r[i] == pytest.approx(one["R"][0, 0, 0], abs=1e-12)
        assert t[i] == pytest.approx(one["T"][0, 0, 0], abs=1e-12)


def test_response_broadcasts_and_keeps_the_stacks_thickness():
    r, t = COATED.response([[1.0], [0.5]], [400.0, 500.0, 600.0])
    assert r.shape == t.shape == (2, 3)
    same = COATED.solve([400.0, 500.0, 600.0], [0.0, 60.0])
    np.testing.assert_allclose(r, same["R"].T, atol=1e-12)
    np.testing.assert_allclose(t, same["T"].T, atol=1e-12)


def test_substrate_side_is_the_reversed_stack():
    reversed_stack = irid.Stack(
        ambient=COATED.substrate, layers=list(reversed(COATED.layers)), substrate=COATED.ambient
    )
    cos_theta = np.linspace(0.05, 1.0, 25)
    r, t = COATED.response(cos_theta, 550.0, 180.0, layer=1, side="substrate")
    # Layer 1 from the ambient is the last one seen from the substrate.
    expected = reversed_stack.solve([550.0], np.degrees(np.arccos(cos_theta)), thickness_nm=[180.0], layer=2)
    np.testing.assert_allclose(r, expected["R"][0, 0], atol=1e-12)
    np.testing.assert_allclose(t, expected["T"][0, 0], atol=1e-12)
    # Past the glass's critical angle nothing leaves into the air.
    critical = np.sqrt(1 - (1 / 1.52) ** 2)
    assert np.all(t[cos_theta < critical - 1e-3] == 0.0)


def test_transmittance_is_reciprocal():
    """T from the substrate at θ_s equals T from the ambient at the angle
    of the same tangential index: what a table of the ambient side relies on."""
    cos_ambient = np.linspace(0.1, 1.0, 19)
    cos_substrate = np.sqrt(1 - (1 - cos_ambient**2) / 1.52**2)
    _, t_front = COATED.response(cos_ambient, 480.0)
    _, t_back = COATED.response(cos_substrate, 480.0, side="substrate")
    np.testing.assert_allclose(t_back, t_front, atol=1e-12)


@pytest.mark.parametrize(
    "kwargs, message",
    [
        ({"cos_theta": 1.2}, "cos_theta: 1.2 is outside [0, 1]"),
        ({"cos_theta": np.nan}, "cos_theta: NaN is outside [0, 1]"),
        ({"thickness_nm": -1.0}, "thickness_nm: must be finite, ≥ 0"),
        ({"thickness_nm": 10.0, "layer": 3}, "layer: must be between 1 and 2 (the stack's layers), got 3"),
        ({"side": "below"}, 'side: expected "ambient" or "substrate", got "below"'),
        ({"wavelength_nm": 0.0}, "wavelength: 0 nm is outside"),
    ],
)
def test_response_bad_input(kwargs, message):
    args = {"cos_theta": 0.5, "wavelength_nm": 500.0}
    args.update(kwargs)
    with pytest.raises(ValueError) as caught:
        COATED.response(**args)
    assert str(caught.value).startswith(message)


def test_no_light_arrives_through_an_absorbing_substrate():
    on_gold = irid.Stack(layers=[(1.5, 100.0)], substrate="gold")
    with pytest.raises(ValueError, match="^side: light cannot arrive through the substrate gold"):
        on_gold.response(0.5, 500.0, side="substrate")


def test_json_round_trip():
    again = irid.Stack.from_json(COATED.to_json())
    assert again.to_json() == COATED.to_json()
    np.testing.assert_array_equal(again.response(0.7, 510.0), COATED.response(0.7, 510.0))
    with pytest.raises(ValueError, match="^stack: not a stack's JSON"):
        irid.Stack.from_json('{"ambient": 1}')
