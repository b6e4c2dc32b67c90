"""Yadav 2020 in full: Kharitonov, robust PI, IMC, H-infinity, interval model, Table 2.

Design procedures are checked on python-control models (controllers/ never sees MuJoCo);
Table 2 is checked against the paper and the twin against the transfer functions.
"""

import itertools
import warnings

import control
import numpy as np
import pytest

from controllers.design.hinf import (
    central_controller,
    gamma_iteration,
    mixed_sensitivity_plant,
    reduce_balanced,
    shift_integrators,
)
from controllers.design.imc import imc_controller
from controllers.design.kharitonov import (
    is_hurwitz,
    kharitonov_polynomials,
    robustly_stable,
    stability_margin_third_order,
)
from controllers.design.robust_pi import design_robust_pi, worst_case_margins
from twin.reproductions.yadav2020 import procedure as r


def _interval(center, rel):
    c = np.asarray(center, float)
    return c * (1 - rel), c * (1 + rel)


# (lower, upper, robustly stable?) for degrees 3 to 5
STABLE = [
    # built on Yadav 2020 eq. (31): its alpha1, alpha2 as lower and beta3 as upper bounds (other bounds ours)
    ([1.0, 7.5, 115.0, 200.0], [1.0, 9.7, 186.0, 273.9]),
    _interval(np.poly([-1, -2, -3, -4]), 0.05),  # (s+1)(s+2)(s+3)(s+4) +-5 %
    _interval(np.poly([-1, -1, -1, -1, -1]), 0.03),  # (s+1)^5 +-3 %
    _interval(np.poly([-0.5, -1 + 2j, -1 - 2j, -3]).real, 0.02),
]
UNSTABLE = [
    ([1.0, 1.0, 1.0, 1.0], [1.0, 2.0, 2.0, 5.0]),  # a1 a2 = 1 < a0 a3 = 5 at a vertex
    _interval(np.poly([-1, -2, -3, -4]), 0.9),  # +-90 %: a vertex loses the Routh test
    _interval(np.poly([-1, -1, -1, -1, -1]), 0.5),  # (s+1)^5 +-50 %
    _interval(np.poly([-0.05, -0.1 + 3j, -0.1 - 3j, -2, -5]).real, 0.2),
]


def _vertex_stable(lo, hi):
    return all(is_hurwitz(np.where(np.array(pick, bool), hi, lo)) for pick in itertools.product((0, 1), repeat=len(lo)))


@pytest.mark.parametrize("lo, hi, expected", [(*b, True) for b in STABLE] + [(*b, False) for b in UNSTABLE])
def test_kharitonov_agrees_with_vertices_and_sampling(lo, hi, expected):
    verdict = robustly_stable(lo, hi)
    assert verdict == expected
    assert verdict == _vertex_stable(np.asarray(lo), np.asarray(hi))
    rng = np.random.default_rng(1)
    samples = rng.uniform(lo, hi, size=(2000, len(lo)))
    sampled = [np.roots(c).real.max() < 0 for c in samples]
    if verdict:
        assert all(sampled)
    else:  # some member is unstable: a vertex (Kharitonov's polynomials are vertices)
        assert not all(is_hurwitz(k) for k in kharitonov_polynomials(lo, hi).values())
    if len(lo) == 4:  # eq. (5): SM > 0 iff robustly stable, for degree 3
        assert (stability_margin_third_order(lo, hi) > 0) == verdict


def test_kharitonov_polynomials_pattern():
    lo, hi = np.array([1.0, 2, 3, 4, 5]), np.array([1.5, 2.5, 3.5, 4.5, 5.5])
    k = kharitonov_polynomials(lo, hi)  # highest power first; K1 = a0(lo) + a1(lo) s + a2(hi) s^2 + ...
    assert k["K1"][::-1].tolist() == [5.0, 4.0, 3.5, 2.5, 1.0]
    assert k["K4"][::-1].tolist() == [5.5, 4.0, 3.0, 2.5, 1.5]


def test_stability_margin_is_the_routh_distance_checked_with_roots():
    """Eq. (5) against numpy's roots, not against the paper's own arithmetic: for the box
    intervals of every controller (ours and the paper's), random intervals and eq. (31)'s,
    SM > 0 with positive coefficients exactly when all 16 corner polynomials are Hurwitz (by
    their roots; our optimal-gamma H-infinity controller truncated to first order gives a
    negative coefficient and SM > 0, the reason eq. (5) needs positive ones), and moving
    beta3 by SM / beta0 puts the worst corner's roots on the imaginary axis (SM = 0 is marginal)."""
    cases = [(row["lower"], row["upper"]) for row in r.interval_table() if len(row["lower"]) == 4]
    rng = np.random.default_rng(3)
    for _ in range(40):
        centre = np.poly(-rng.uniform(0.2, 5.0, 3))
        cases.append(_interval(centre, rng.uniform(0.01, 0.6)))
    p = r.PAPER["pi_interval"]
    cases.append(([1.0, p["alpha1"], p["alpha2"], 200.0], [1.0, 9.7, 186.0, p["beta3"]]))
    assert len(cases) > 45
    assert any(stability_margin_third_order(lo, hi) < 0 for lo, hi in cases)
    for lo, hi in cases:
        lo, hi = np.asarray(lo, float), np.asarray(hi, float)
        sm = stability_margin_third_order(lo, hi)
        corners = [np.where(np.array(pick, bool), hi, lo) for pick in itertools.product((0, 1), repeat=4)]
        all_hurwitz = all(np.roots(c).real.max() < 0 for c in corners)
        assert all_hurwitz == (sm > 0 and (lo > 0).all()), (lo, hi, sm)  # eq. (5) presumes positive coefficients
        marginal = np.roots([hi[0], lo[1], lo[2], hi[3] + sm / hi[0]])
        assert abs(marginal.real.max()) < 1e-6 * np.abs(marginal).max()


def test_interval_model_is_exact_over_the_box():
    """The coefficient bounds equal the min/max over all 16 vertices and bound random samples."""
    nominal = r.nominal_params()
    for ctrl in r.TABLE2_CONTROLLERS.values():
        lo, hi = r.coefficient_interval(ctrl)
        vert = np.array([r.characteristic_coefficients(ctrl, r.plant_gain(v), v) for v in r.box_vertices(nominal)])
        assert np.allclose(lo, vert.min(axis=0))
        assert np.allclose(hi, vert.max(axis=0))
        rand = np.array([r.characteristic_coefficients(ctrl, r.plant_gain(p), p) for p in r.random_samples(300, 2)])
        assert (rand >= lo - 1e-9).all()
        assert (rand <= hi + 1e-9).all()
    # eq. (30) at nominal: s^3 + 9.697 s^2 + 4.848 Kp s + 4.848 Ki
    c = r.characteristic_coefficients(r.TABLE2_CONTROLLERS["robust_pi"], r.plant_gain(nominal), nominal)
    assert c == pytest.approx([1.0, 9.697, 4.848 * 38.33, 4.848 * 45.65], rel=1e-3)


def test_robust_pi_design_lands_on_the_paper_gains():
    d = design_robust_pi(7.5, 3.0, 6.0, gm_db=10.0, pm_deg=60.0)  # eq. (17)'s coefficients
    assert d.kp == pytest.approx(38.33, rel=0.02)
    assert d.ki == pytest.approx(45.65, rel=0.02)
    gm, pm = worst_case_margins(7.5, 3.0 * d.kp, 6.0 * d.ki)
    assert (gm, pm) == pytest.approx((10.0, 60.0))
    with pytest.raises(ValueError, match="pm_deg"):
        design_robust_pi(7.5, 3.0, 6.0, pm_deg=95.0)


def test_imc_reproduces_eq23_and_first_order_form():
    C = imc_controller(control.tf([4.85], [1.0, 9.7, 0.0]), 1.0, 2)
    num, den = (np.squeeze(x) for x in control.tfdata(C))
    num, den = num / den[0], den / den[0]
    assert round(num[0], 2) == 0.21
    assert num[1] == pytest.approx(2.0)
    assert den == pytest.approx([1.0, 2.0])
    # first-order plant k/(s + d), lambda = 1: C = (s + d)/(k mu s), a PI
    C1 = imc_controller(control.tf([2.0], [1.0, 3.0]), 0.5, 1)
    assert control.tf(C1).num[0][0] == pytest.approx([1.0, 3.0])
    assert control.tf(C1).den[0][0] == pytest.approx([1.0, 0.0])
    with pytest.raises(ValueError, match="lam"):
        imc_controller(control.tf([4.85], [1.0, 9.7, 0.0]), 1.0, 1)
    for row, paper in zip(r.imc_design()["table3"], r.PAPER["table3"]):
        assert (row["damping"], row["wn_rad_s"], row["st_4_over_xi_wn_s"]) == pytest.approx(
            (paper[1], paper[2], paper[4]), rel=1e-5
        )


def test_hinf_gamma_iteration_and_reduction():
    """Reported beside eqs. (28)-(29): no threshold on the match, but gamma must respect its
    lower bound |W3(0) T(0)| = 10 (integral action makes T(0) = 1) and be admissible."""
    s = control.tf("s")
    P = mixed_sensitivity_plant(
        shift_integrators(control.tf([4.85], [1.0, 9.7, 0.0]), 1e-6), 20 / (s + 0.01), control.tf(1, 1), 1 / (s + 0.1)
    )
    it = gamma_iteration(P)
    assert 10.0 <= it.gamma <= 10.1
    # python-control's own mixsyn (SB10AD's optimizer) on the same weights agrees
    with warnings.catch_warnings():  # python-control 0.10's mixsyn calls its own deprecated connect()
        warnings.filterwarnings("ignore", message=r"connect\(\) is deprecated", category=FutureWarning)
        _, _, (gamma_mixsyn, _) = control.mixsyn(
            shift_integrators(control.tf([4.85], [1.0, 9.7, 0.0]), 1e-6),
            20 / (s + 0.01),
            control.tf(1, 1),
            1 / (s + 0.1),
        )
    assert it.gamma == pytest.approx(gamma_mixsyn, rel=0.01)
    with pytest.raises(ValueError, match="no admissible"):
        central_controller(P, 9.0)
    assert central_controller(P, 1 / r.PAPER["hinf_theta"]).nstates == 4  # the paper's order
    # balanced truncation of the published eq. (28) to first order gives eq. (29)
    red = reduce_balanced(r.HINF_EQ28, 1)
    num, den = red.num[0][0], red.den[0][0]
    assert num[-1] / den[0] == pytest.approx(20.97, rel=0.005)
    assert den[1] / den[0] == pytest.approx(5.5, rel=0.01)


def test_hinf_design_reports_the_gamma_floor_it_computes():
    """The reported floor |W3(0) T(0)| is computed from the design: W3(0) = 10 and T(0) just below
    1 (the integrator is shifted by 1e-6), and the optimal gamma respects it."""
    d = r.hinf_design()
    assert 9.99 < d["gamma_floor_W3T_at_dc"] < 10.0 <= d["gamma_opt"]
    g0 = 4.85 / (1e-6 * 9.7)  # eq. (2) at s = 0 with the integrator moved to -1e-6
    k = d["controller_opt"]
    loop0 = g0 * k["num"][-1] / k["den"][-1]
    assert d["gamma_floor_W3T_at_dc"] == pytest.approx(10.0 * loop0 / (1 + loop0), rel=1e-6)


def test_table2_nominal_on_transfer_functions():
    """Settling times and the non-trivial overshoots within 5 % of Table 2; the paper's RT is
    the 0-100 % rise time where the response overshoots and 10-90 % for IMC (never reaches 1)."""
    nominal = r.nominal_params()
    m = {name: r.tf_step(c, nominal) for name, c in r.TABLE2_CONTROLLERS.items()}
    for name, row in r.PAPER["table2"].items():
        assert m[name]["settling_time_s"] == pytest.approx(row["nominal"][1], rel=0.05)
    assert m["robust_pi"]["overshoot_pct"] == pytest.approx(41.2, rel=0.05)
    assert m["hinf"]["overshoot_pct"] == pytest.approx(6.3, rel=0.05)
    assert m["robust_pi"]["rise_time_0_100_s"] == pytest.approx(0.14, rel=0.05)
    assert m["hinf"]["rise_time_0_100_s"] == pytest.approx(1.12, rel=0.05)
    assert m["imc"]["rise_time_10_90_s"] == pytest.approx(3.36, rel=0.05)
    # the 0.1 s delay of eq. (2): the robust PI loop is unstable with it, IMC is not
    assert r.tf_step(r.TABLE2_CONTROLLERS["robust_pi"], nominal, delay_s=0.1) is None
    assert r.tf_step(r.TABLE2_CONTROLLERS["imc"], nominal, delay_s=0.1) is not None


def test_twin_matches_transfer_functions_on_table2_nominal():
    nominal = r.nominal_params()
    for name, ctrl in r.TABLE2_CONTROLLERS.items():
        tf, twin = r.tf_step(ctrl, nominal), r.twin_step(ctrl, nominal)
        for k in ("overshoot_pct", "settling_time_s", "rise_time_10_90_s"):
            assert twin[k] == pytest.approx(tf[k], rel=0.02, abs=0.1 if k == "overshoot_pct" else 0), (name, k)


@pytest.mark.slow
def test_table2_bands_small_counts():
    t2 = r.table2(mc_samples=20, twin_random=1, seed=3, progress=False)
    assert not t2.mismatches
    row = t2.rows["robust_pi"]
    lo, hi = row["tf_paper_samples"]["overshoot_pct"]
    assert lo < row["tf_nominal"]["overshoot_pct"] < hi
    assert row["twin_paper_samples"]["overshoot_pct"] == pytest.approx((lo, hi), rel=0.02)


def test_sampled_step_response_matches_scipy_across_blocks():
    """The block-wise state-space step response against scipy's dlsim (stepped one sample at a
    time) on a stable 3-state system, over 2 500 samples: 2.5 blocks of 1 000."""
    from scipy.signal import dlsim

    rng = np.random.default_rng(0)
    A = np.diag([0.999, 0.95, -0.5]) + 0.01 * rng.standard_normal((3, 3))
    B, C, D = rng.standard_normal((3, 1)), rng.standard_normal((1, 3)), np.array([[0.3]])
    _, expected, _ = dlsim((A, B, C, D, 1.0), np.ones(2500))
    np.testing.assert_allclose(r.sampled_step_response(A, B, C, D, n=2500), expected[:, 0], rtol=1e-9, atol=1e-12)


def test_our_designs_stand_beside_the_printed_controllers():
    """Table 2's columns of ours: the unrounded robust PI and our IMC are within rounding of the
    printed ones (overshoot within 0.5 point, settling within 2 %); our H-infinity central
    controller at the paper's gamma overshoots about 4 % as eq. (28) does (the printed Table 2
    row is the reduced eq. 29); at the optimal gamma, balanced truncation to first order keeps
    the shifted integrator's slow mode with a negative gain and the loop is unstable."""
    nominal = r.nominal_params()
    ours = r.our_controllers()
    for mine, printed in (("robust_pi_ours", "robust_pi"), ("imc_ours", "imc")):
        a, b = r.tf_step(ours[mine], nominal), r.tf_step(r.TABLE2_CONTROLLERS[printed], nominal)
        assert abs(a["overshoot_pct"] - b["overshoot_pct"]) < 0.5
        assert a["settling_time_s"] == pytest.approx(b["settling_time_s"], rel=0.02)
    eq28 = r.tf_step(r.HINF_EQ28, nominal)
    assert r.tf_step(ours["hinf_ours_paper_gamma"], nominal)["overshoot_pct"] == pytest.approx(
        eq28["overshoot_pct"], abs=0.2
    )
    assert r.tf_step(ours["hinf_ours_optimal_reduced"], nominal) is None
