"""The materials library: the Kienzle fits reproduce their source's values, every entry names
its source, the Kienzle force is kc1 h^(1 - mc) b, the linear entries' forces are the linear
model's bit for bit, and a user's bad Kienzle values are refused with the field named."""

import math

import numpy as np
import pytest
from pydantic import ValidationError

from twin.machining.cutting import (
    CoefficientsSpec,
    kienzle_coefficients,
    mean_tool_forces_N,
    step_tool_forces_N,
)
from twin.machining.materials import (
    KIENZLE_AXIAL_RATIO,
    KIENZLE_RADIAL_RATIO,
    MATERIALS,
    CuttingCoefficients,
    fit_kienzle,
    kienzle,
)

#: Mitsubishi Materials, technical information, "Cutting Power for Face Milling", the Kc table
#: (Kc in MPa at a feed per tooth of 0.1, 0.2, 0.3, 0.4, 0.6 mm/tooth), typed here from the page
#: independently of the library's copy: the entry fitted to each row.
FEEDS_MM = (0.1, 0.2, 0.3, 0.4, 0.6)
MITSUBISHI_ROWS = {
    "steel_mild_520": (2200, 1950, 1820, 1700, 1580),  # Mild Steel, 520 MPa
    "steel_medium_620": (1980, 1800, 1730, 1600, 1570),  # Medium Steel, 620 MPa
    "steel_cr_mo_730": (2540, 2250, 2140, 2000, 1800),  # Chrome Molybdenum Steel, 730 MPa
    "stainless_austenitic": (2030, 1970, 1900, 1770, 1710),  # Austenitic Stainless Steel, 155 HB
    "cast_iron_grey": (1750, 1400, 1240, 1050, 970),  # Grey Cast Iron, 200 HB
    "brass": (1150, 950, 800, 700, 630),  # Brass, 500 MPa
}
#: The fits' largest relative residual as the docs state it (rounded up).
STATED_RESIDUAL = {
    "steel_mild_520": 0.010,
    "steel_medium_620": 0.026,
    "steel_cr_mo_730": 0.024,
    "stainless_austenitic": 0.025,
    "cast_iron_grey": 0.045,
    "brass": 0.034,
}


@pytest.mark.parametrize("name", sorted(MITSUBISHI_ROWS))
def test_the_fitted_kienzle_law_reproduces_the_sources_kc_at_each_feed(name):
    material = MATERIALS[name].value
    k = material.coefficients
    kc = np.array(MITSUBISHI_ROWS[name], float)
    predicted = k.K_tc * np.array(FEEDS_MM) ** -k.mc
    assert material.fit is not None
    assert np.abs(predicted / kc - 1).max() == pytest.approx(material.fit.max_relative_residual, rel=1e-9)
    assert np.abs(predicted / kc - 1).max() <= STATED_RESIDUAL[name]
    assert f"{material.fit.max_relative_residual:.1%}" in material.source


def test_the_fit_recovers_an_exact_power_law():
    h = np.array(FEEDS_MM)
    fit = fit_kienzle(h, 1700.0 * h**-0.25)
    assert (fit.kc1_N_per_mm2, fit.mc) == pytest.approx((1700.0, 0.25), rel=1e-12)
    assert fit.max_relative_residual < 1e-12


def test_every_entry_names_its_source_and_kienzle_entries_use_our_stated_ratios():
    kinds = set()
    for name, entry in MATERIALS.items():
        material = entry.value
        assert material.source.strip(), name
        k = material.coefficients
        assert 0.0 <= k.mc < 1.0, name
        if k.mc:
            kinds.add(name.split("_")[0])
            assert (k.K_rc, k.K_ac) == pytest.approx((KIENZLE_RADIAL_RATIO * k.K_tc, KIENZLE_AXIAL_RATIO * k.K_tc))
            assert (k.K_te, k.K_re, k.K_ae) == (0.0, 0.0, 0.0)
    assert {"steel", "stainless", "cast", "brass", "titanium"} <= kinds
    # the ratios lie within those of the sourced linear entries
    linear = [e.value.coefficients for e in MATERIALS.values() if not e.value.coefficients.mc]
    assert min(k.K_rc / k.K_tc for k in linear) <= KIENZLE_RADIAL_RATIO <= max(k.K_rc / k.K_tc for k in linear)
    assert min(k.K_ac / k.K_tc for k in linear) <= KIENZLE_AXIAL_RATIO <= max(k.K_ac / k.K_tc for k in linear)


def test_the_kienzle_force_at_a_chip_thickness_is_kc1_h_to_the_1_minus_mc_times_b():
    """A narrow arc at phi = 90 deg cuts h = c: F_t = kc1 c^(1 - mc) a, F_r its radial ratio."""
    k = MATERIALS["steel_cr_mo_730"].value.coefficients
    c, a, half = 0.15, 2.0, 1e-4
    st, ex = math.pi / 2 - half, math.pi / 2 + half
    by_hand = k.K_tc * c ** (1.0 - k.mc) * a
    # flute 0 sweeps the whole arc within the step: the step's force is the arc's integral / step
    step = 4 * half
    fx, fy, fz = step_tool_forces_N(
        kienzle_coefficients(k.as_array(), c, st, ex), 1, a, np.array([c]), np.zeros(1), st, ex, st - half, step, 0.0
    )
    arc = (ex - st) / step
    assert fy / arc == pytest.approx(by_hand, rel=1e-6)  # F_y = F_t at 90 deg
    assert -fx / arc == pytest.approx(KIENZLE_RADIAL_RATIO * by_hand, rel=1e-6)
    assert fz / arc == pytest.approx(KIENZLE_AXIAL_RATIO * by_hand, rel=1e-6)


def test_the_kienzle_mean_force_is_kc_at_the_mean_chip_thickness():
    """Over a slot the mean torque-producing force is kc(h_m) times the mean chip area."""
    k = MATERIALS["titanium_alpha_beta"].value.coefficients
    c, a = 0.1, 3.0
    h_m = 2 * c / math.pi  # a slot's mean chip thickness
    linear = CuttingCoefficients(k.K_tc * h_m**-k.mc, k.K_rc * h_m**-k.mc, k.K_ac * h_m**-k.mc, 0.0, 0.0, 0.0)
    np.testing.assert_allclose(
        mean_tool_forces_N(k, n_flutes=4, axial_depth_mm=a, feed_per_tooth_mm=c, phi_st=0.0, phi_ex=math.pi),
        mean_tool_forces_N(linear, n_flutes=4, axial_depth_mm=a, feed_per_tooth_mm=c, phi_st=0.0, phi_ex=math.pi),
        rtol=1e-12,
    )


def test_the_linear_entries_pass_through_unchanged():
    for name, entry in MATERIALS.items():
        material = entry.value
        k = material.coefficients.as_array()
        if not material.coefficients.mc:
            assert kienzle_coefficients(k, 0.1, 0.0, math.pi) is k, name
    # and the aluminium default's force is the linear model's, exactly
    k = MATERIALS["aluminium_7075_t6"].value.coefficients
    full = step_tool_forces_N(k.as_array(), 3, 2.0, np.full(3, 0.1), np.zeros(3), 0.0, math.pi, 0.3, 0.01, 0.0)
    six = step_tool_forces_N(k.as_array()[:6], 3, 2.0, np.full(3, 0.1), np.zeros(3), 0.0, math.pi, 0.3, 0.01, 0.0)
    assert full == six


def test_no_chip_no_kienzle_scaling():
    k = MATERIALS["brass"].value.coefficients.as_array()
    assert kienzle_coefficients(k, 0.0, 0.0, math.pi) is k


def test_a_users_kienzle_form_and_linear_coefficients():
    user = CoefficientsSpec(kc1_N_per_mm2=1800.0, mc=0.25).applied_to("aluminium_7075_t6")
    assert user == kienzle(1800.0, 0.25)
    over = CoefficientsSpec(kc1_N_per_mm2=1800.0, mc=0.25, K_rc=900.0).applied_to("steel_mild_520")
    assert (over.K_tc, over.K_rc, over.mc) == (1800.0, 900.0, 0.25)
    linear = CoefficientsSpec(K_tc=500.0).applied_to("aluminium_6082_t6")
    assert linear.K_tc == 500.0
    assert linear.mc == 0.0


@pytest.mark.parametrize(
    ("given", "field", "words"),
    [
        ({"kc1_N_per_mm2": -5.0, "mc": 0.2}, "kc1_N_per_mm2", "greater than 0"),
        ({"kc1_N_per_mm2": 1500.0, "mc": 1.2}, "mc", "less than 1"),
        ({"kc1_N_per_mm2": 1500.0, "mc": -0.1}, "mc", "greater than or equal to 0"),
        ({"kc1_N_per_mm2": 1500.0}, "", "kc1_N_per_mm2 needs mc"),
        ({"mc": 0.2}, "", "mc needs kc1_N_per_mm2"),
        ({"kc1_N_per_mm2": 1500.0, "mc": 0.2, "K_tc": 700.0}, "", "not both"),
    ],
)
def test_a_bad_user_kienzle_value_is_one_error_naming_the_field(given, field, words):
    with pytest.raises(ValidationError) as err:
        CoefficientsSpec(**given)
    errors = err.value.errors()
    assert len(errors) == 1
    assert ".".join(str(p) for p in errors[0]["loc"]) == field
    assert words in errors[0]["msg"]
