"""Choi 1999: Glover-McFarlane loop shaping, reduction, mu analysis, ZPETC and the circle tests."""

from __future__ import annotations

import copy
import itertools

import control
import numpy as np
import pytest

from controllers.design.hinf import gamma_iteration
from controllers.design.mimo import frequency_response
from controllers.design.mu import constant_upper_lft, destabilizing_scale, mu_upper_bound
from controllers.design.ncf import (
    central_controller,
    gamma_min,
    ncf_generalized_plant,
    ncf_riccati,
    ncf_robustness_norm,
)
from controllers.design.pid import pid_for_crossover, pid_for_crossover_with_kp, pid_tf
from controllers.design.zpetc import damping_ratio, zpetc
from controllers.papers import choi1999 as s4
from twin.reproductions.choi1999 import procedure as r


def _shaped():
    d = s4.mimo_design()["design"].shaped
    return d.A, d.B, d.C


def test_riccati_solutions_solve_their_equations():
    A, B, C = _shaped()
    X, Z = ncf_riccati(A, B, C)
    care = A.T @ X + X @ A - X @ B @ B.T @ X + C.T @ C
    fare = A @ Z + Z @ A.T - Z @ C.T @ C @ Z + B @ B.T
    assert np.abs(care).max() < 1e-8 * np.abs(X).max() * np.abs(A).max()
    assert np.abs(fare).max() < 1e-8 * np.abs(Z).max() * np.abs(A).max()


def test_gamma_min_matches_sb10ad_on_the_ncf_generalized_plant():
    A, B, C = _shaped()
    ours = gamma_min(A, B, C)
    independent = gamma_iteration(
        ncf_generalized_plant(A, B, C), gamma_max=100.0, gamma_min=1.0 + 1e-6, tol=1e-6, ncon=2, nmeas=2
    ).gamma
    assert abs(ours - independent) < 0.01 * independent
    assert 1.0 < ours < 4.0  # a sensible loop shape (Skogestad: gamma_min < 4)


def test_central_controller_achieves_its_gamma_and_not_below_gamma_min():
    A, B, C = _shaped()
    g_min = gamma_min(A, B, C)
    K = central_controller(A, B, C, 1.1 * g_min)
    achieved = ncf_robustness_norm(A, B, C, K, omega=np.logspace(-1, 5, 800))
    assert g_min * 0.999 < achieved <= 1.1 * g_min * 1.001
    with pytest.raises(ValueError, match="must exceed gamma_min"):
        central_controller(A, B, C, 0.99 * g_min)


def test_controller_orders_are_the_papers():
    d = s4.mimo_design()
    assert (control.ss(d["full"]).nstates, control.ss(d["reduced"]).nstates) == (8, 4)
    assert len(d["dropped"]) == 4
    assert np.all(d["dropped"] <= d["hankel"][3])


def test_reduced_controller_stable_on_every_corner_of_table1():
    K = s4.controller_si("mimo")
    box = s4.stable_range_claim()["table1_box"]
    for k_il, k_c, *signs in itertools.product(box["k_il"], box["k_c"], *[(-1.0, 1.0)] * 4):
        p = s4.nominal_params()
        for key, sg in zip(("m_x", "m_y", "b_x", "b_y"), signs):
            p[key] *= 1.0 + sg * s4.TABLE1[key][1]
        cl = control.feedback(s4.plant_si(k_il, k_c, p) * control.ss(K), np.eye(2))
        assert np.max(cl.poles().real) < 0, f"unstable at k_il {k_il}, k_c {k_c}, m/b signs {signs}"


def test_uncertain_plant_is_the_perturbed_plant():
    """Closing the real channels with a constant delta gives eq. (11) with the perturbed values."""
    P = s4.uncertain_plant(False)
    delta = np.array([0.5, 0.0, -0.3, 0.2, 0.0, 1.0, -0.3, 0.2, 0.4, 0.0])
    Pu = control.ss(*constant_upper_lft(P, delta))
    p = s4.nominal_params()
    p["m_x"] *= 1 + 0.3 * 0.5
    p["b_y"] *= 1 + 0.2
    w = np.logspace(-1, 4, 40)
    G = frequency_response(s4.design_plant(-2500 * (1 - 1.1 * 0.3), 2500 * (1 + 1.1 * 0.2), p), w)
    G[:, :, 0] *= (1 + 0.4 * (1j * w + 600) / (1j * w + 2000))[:, None]
    np.testing.assert_allclose(frequency_response(Pu, w), -G, rtol=1e-9, atol=1e-12)


def test_mu_upper_bound_bounds_the_sampled_destabilizing_perturbations():
    N, _ = r.perturbation_loops("mimo")
    bound = mu_upper_bound(N, np.logspace(-1, 4, 121), *s4.robust_stability_structure()).max()
    directions = [np.array(c) for c in itertools.product((-1.0, 1.0), repeat=10)][::16]
    k_min = min(destabilizing_scale(N, d, 3.0) for d in directions)
    assert np.isfinite(k_min)  # some scaled corner does destabilize
    assert bound >= 1.0 / k_min
    assert bound < 1.0  # robustly stable over Table 1's box and the amplifier weight


def test_pid_for_crossover_meets_its_targets():
    def plant(w):
        s = 1j * np.asarray(w, float)
        return 98.2 / (s * (52.3 * s + 2693.5))

    kp, ki, kd, tf_s = pid_for_crossover(plant, 700.0, 60.0)
    L = pid_tf(kp, ki, kd, tf_s)(700j) * plant(np.array([700.0]))[0]
    assert abs(abs(L) - 1.0) < 1e-9
    assert abs(np.degrees(np.angle(L)) + 120.0) < 1e-6


def test_zpetc_gives_zero_phase_and_unit_dc_gain():
    """A loop with a zero outside the unit circle (z = -1.5): T F has zero phase everywhere."""
    num = np.array([0.0, 0.2, 0.3])  # z^-1 (0.2 + 0.3 z^-1): zero at -1.5
    den = np.array([1.0, -0.9, 0.4])  # stable
    f = zpetc(num, den)
    assert f.delay == 1
    assert f.preview == 2
    assert np.allclose(f.unacceptable, [-1.5])
    w = np.linspace(0.01, 3.0, 50)
    resp = f.response(num, den, w)
    np.testing.assert_allclose(np.angle(resp), 0.0, atol=1e-9)
    assert abs(f.response(num, den, [0.0])[0] - 1.0) < 1e-12


def test_zpetc_inverts_a_well_damped_zero_near_one_and_not_one_near_minus_one():
    """Zeros at z = 0.9996 (a PI's slow zero, damping ratio 1) and z = -0.999 (a Tustin zero):
    the first is inverted, the second left out.  Left out, the zero near +1 would divide the
    filter by B_u(1)^2 = 1.6e-7 (the twin's PID loop with ki/100 ran away that way)."""
    zeros, poles = (0.9996, -0.999), (0.5, 0.3, 0.2)
    num = np.concatenate([[0.0], np.real(np.poly(zeros))])  # z^-1 (1 - 0.9996 z^-1)(1 + 0.999 z^-1)
    den = np.real(np.poly(poles))
    f = zpetc(num, den)
    assert np.allclose(f.unacceptable, [-0.999])
    assert f.preview == 2
    assert abs(f.response(num, den, [0.0])[0] - 1.0) < 1e-9
    filter_poles = np.roots(f.den)  # ascending in z^-1: roots are the poles in z
    assert np.allclose(filter_poles, [0.9996])
    assert max(abs(c) for c in f.num) < 1e4  # 1 / (B_u(1)^2 (1 - 0.9996)) would be ~1e10
    assert damping_ratio(0.9996) == pytest.approx(1.0)
    assert damping_ratio(-0.999) < 1e-3


def test_zpetc_reduces_the_air_cut_tracking_error():
    kw = dict(radius_mm=20.0, feed=2400.0, duration_s=0.6)
    with_ff = r.tf_circle("mimo", zpetc=True, **kw)["max_tracking_settled_um"]
    without = r.tf_circle("mimo", zpetc=False, **kw)["max_tracking_settled_um"]
    assert max(with_ff) < 0.2 * max(without)


def test_twin_matches_transfer_function_loop_within_2_percent():
    data = copy.deepcopy(r.scenario_data("choi1999_mimo_cutting"))
    data["disturbances"] = [dict(r.AVERAGE_FORCE, harmonic_fraction=0.0)]
    data["duration_s"] = 0.6
    data.pop("overrides")
    data.pop("sensors")
    twin = r.twin_errors(r.run_twin(data))
    tf = r.tf_circle(
        "mimo",
        zpetc=True,
        radius_mm=28.0,
        feed=4800.0,
        duration_s=0.6,
        k_il=r.AVERAGE_FORCE["k_il_N_s_per_m"],
        k_c=r.AVERAGE_FORCE["k_c_N_s_per_m"],
    )
    for key in ("max_tracking_settled_um", "max_contour_path_um"):
        np.testing.assert_allclose(twin[key], tf[key], rtol=0.02)
    assert twin["max_tracking_settled_um"][0] > 10.0  # the cutting force does deflect the table


def test_choi1999_controllers_need_both_axes_and_the_design_period():
    from controllers import make_controller

    with pytest.raises(ValueError, match="serve axes x and y together"):
        make_controller("choi1999_mimo", s4.DT_S, axes=("x",))
    with pytest.raises(ValueError, match=r"designed for 0\.0005 s"):
        make_controller("choi1999_pid", 1e-3, axes=("x", "y"))
    with pytest.raises(ValueError, match="zpetc"):
        make_controller("choi1999_mimo", s4.DT_S, {"zpetc": 3.0}, axes=("x", "y"))


def test_pid_for_crossover_with_kp_crosses_over_with_the_given_kp():
    def plant(w):
        s = 1j * np.asarray(w, float)
        return 98.2 / (s * (52.3 * s + 2693.5))

    kp, ki, kd, tf_s = pid_for_crossover_with_kp(plant, 700.0, 4.0e4)
    assert kp == 4.0e4
    assert ki == pytest.approx(4.0e4 * 70.0)
    assert kd > 0
    assert abs(pid_tf(kp, ki, kd, tf_s)(700j) * plant(np.array([700.0]))[0]) == pytest.approx(1.0, abs=1e-9)
    with pytest.raises(ValueError, match="no kd >= 0"):
        pid_for_crossover_with_kp(plant, 700.0, 1e7)


def test_mimo_static_gain_and_the_pid_matched_to_it():
    """K(0) = D - C A^-1 B of the state-space controller, computed here with numpy; the
    'mimo_diagonal' PID takes its diagonal as kp (V/m)."""
    for order in ("full", "reduced"):
        K = control.ss(s4.mimo_design()[order])
        expected = K.D - K.C @ np.linalg.solve(K.A, K.B)
        np.testing.assert_allclose(s4.mimo_static_gain_V_per_m(order), expected, rtol=1e-9)
    kps = [g[0] for g in s4.pid_design("mimo_diagonal")["gains"]]
    np.testing.assert_allclose(kps, np.diag(s4.mimo_static_gain_V_per_m("reduced")), rtol=1e-12)


def test_static_gain_sets_the_cutting_error():
    """A PD with the MIMO controller's K(0) as kp and its diagonal crossover cuts the R 28 circle
    within 10 % of the MIMO controller's tracking errors; any integral action takes them far below."""
    runs = {}
    for name, params in (
        ("mimo", None),
        ("pd", {"tuning": "mimo_diagonal", "ki_scale": 0.0}),
        ("pid", {"tuning": "mimo_diagonal"}),
    ):
        data = r.scenario_data("choi1999_mimo_cutting")
        if params is not None:
            data["controller"] = {"type": "choi1999_pid", "params": params}
        runs[name] = np.array(r.twin_errors(r.run_twin(data))["max_tracking_settled_um"])
    np.testing.assert_allclose(runs["pd"], runs["mimo"], rtol=0.1)
    assert (runs["pid"] < 0.25 * runs["mimo"]).all()
