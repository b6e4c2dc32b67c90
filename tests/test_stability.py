"""Stability lobes (twin.machining.stability) against closed forms and a second implementation
written here from the papers.

The Insperger-Stepan benchmark (Insperger and Stepan, Int. J. Numer. Meth. Eng. 61 (2004)
117-141, section 5; the same in Insperger, Mann, Stepan, Bayly, Int. J. Mach. Tools Manuf. 43
(2003) 25-34): one mode in x, 2 teeth, K_t = 6e8 N/m^2, K_n = 2e8 N/m^2, omega_n = 2 pi 922
rad/s, zeta = 0.011, m = 0.03993 kg, full slot and a/D = 0.05 down milling, the equation
``m x'' + c x' + k x = -w h(t) (x(t) - x(t - tau))`` with ``h(t) = sum_j g_j sin(phi_j) (K_t
cos(phi_j) + K_n sin(phi_j))`` (eqs. 43-45 of the 2004 paper).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import quad

from twin.machining.stability import Cut, sd_critical_depths, zoa_critical_depths
from twin.machining.tool_dynamics import ToolDynamicsSpec

MASS, F_N, ZETA, K_T, K_N, TEETH = 0.03993, 922.0, 0.011, 6e8, 2e8, 2
OMEGA_N = 2 * math.pi * F_N
STIFFNESS = MASS * OMEGA_N**2
BENCHMARK = ToolDynamicsSpec.model_validate(
    {"modes": [{"direction": "x", "frequency_hz": F_N, "damping_ratio": ZETA, "modal_mass_kg": MASS}]}
)
SLOT = (0.0, math.pi)
DOWN_005 = (math.acos(2 * 0.05 - 1), math.pi)  # a/D = 0.05 down milling: arccos(2 a/D - 1) .. pi


def benchmark_cut(arc):
    return Cut(TEETH, K_T, K_N / K_T, ((arc[0], arc[1], 1.0),))


def insperger_h(phi, arc):
    """Insperger's specific force at a flute angle (N/m^2), zero out of the cut."""
    return np.where((phi >= arc[0]) & (phi <= arc[1]), np.sin(phi) * (K_T * np.cos(phi) + K_N * np.sin(phi)), 0.0)


def averaged_h(arc) -> float:
    """The mean of h(t) over a tooth period (the averaged equation's coefficient)."""
    return TEETH / (2 * math.pi) * quad(lambda p: float(insperger_h(np.array(p), arc)), arc[0], arc[1])[0]


class OrthogonalCut:
    """Orthogonal cutting (turning) of width ``w`` against one mode in x: ``F_x = -K_f w (x(t) -
    x(t - T))`` once a revolution, so the force matrix is constant (the solvers' interface)."""

    n_flutes = 1

    def __init__(self, k_f: float):
        self.k_f = k_f

    def tooth_period_s(self, spindle_rpm):
        return 60.0 / np.asarray(spindle_rpm, float)

    def mean_matrix(self):
        return np.array([[-self.k_f, 0.0], [0.0, 0.0]])

    def step_matrices(self, steps):
        return np.full(steps, 1.0 / steps), np.broadcast_to(self.mean_matrix(), (steps, 2, 2)).copy()


def test_orthogonal_cutting_minimum_width_is_the_closed_form():
    """Tobias/Tlusty: the lowest critical width of one mode is 2 k zeta (1 + zeta) / K_f
    (Altintas, Manufacturing Automation, eq. 3.26); both solvers reach it at a lobe's bottom."""
    k_f = 2e9
    closed = 2 * STIFFNESS * ZETA * (1 + ZETA) / k_f
    rpm = np.linspace(20000, 60000, 400)
    zoa = zoa_critical_depths(OrthogonalCut(k_f), BENCHMARK, rpm)
    assert np.nanmin(zoa.critical_depth_m) == pytest.approx(closed, rel=5e-3)
    sd = sd_critical_depths(OrthogonalCut(k_f), BENCHMARK, spindle_rpm=rpm[::4], depth_max_m=5 * closed, n_depths=20)
    assert np.nanmin(sd.critical_depth_m) == pytest.approx(closed, rel=2e-2)
    # above the lowest, never below it
    assert np.nanmin(sd.critical_depth_m) >= closed * 0.99


@pytest.mark.parametrize(("arc", "sign"), [(SLOT, 1.0), (DOWN_005, -1.0)])
def test_zero_order_minimum_is_the_averaged_closed_form(arc, sign):
    """One mode, the averaged equation m x'' + c x' + k x = -w h0 (x - x(t - tau)): its lowest
    critical depth is 2 k zeta (1 + zeta) / h0 for h0 > 0 (the real part of the receptance's
    minimum, -1/(4 k zeta (1 + zeta))) and 2 k zeta (1 - zeta) / |h0| for h0 < 0 (its maximum).
    Slot: h0 = N K_n / 4 = 1e8 N/m^2, 0.298 mm; a/D = 0.05 down milling: h0 < 0, 1.79 mm."""
    h0 = averaged_h(arc)
    assert np.sign(h0) == sign
    closed = 2 * STIFFNESS * ZETA * (1 + sign * ZETA) / abs(h0)
    lobes = zoa_critical_depths(benchmark_cut(arc), BENCHMARK, np.linspace(5000, 25000, 200))
    assert np.nanmin(lobes.critical_depth_m) == pytest.approx(closed, rel=0.02)
    assert np.nanmin(lobes.critical_depth_m) >= closed * (1 - 1e-6)


def reference_spectral_radius(arc, spindle_rpm: float, depth_m: float, steps: int = 256) -> float:
    """The monodromy of Insperger's equation by fourth-order Runge-Kutta on ``steps`` equal steps
    of a tooth period, the delayed state between grid points by cubic Hermite interpolation
    from the stored positions and velocities of one period before (a second implementation:
    none of the semi-discretization's exponentials, step averages or linear interpolation)."""
    tau = 60.0 / (TEETH * spindle_rpm)
    dt = tau / steps
    omega = 2 * math.pi * spindle_rpm / 60.0

    def h_of(t):
        return sum(
            insperger_h(np.array(math.fmod(omega * t + j * 2 * math.pi / TEETH, 2 * math.pi)), arc)
            for j in range(TEETH)
        )

    def rhs(t, x, v, x_delayed):
        return v, (-2 * ZETA * OMEGA_N * v - OMEGA_N**2 * x - depth_m * h_of(t) / MASS * (x - x_delayed))

    n = 2 * (steps + 1)
    # history[p] = (x, v) at t_i - tau + p dt, p = 0..steps, each a row of n columns (basis)
    hist_x = np.zeros((steps + 1, n))
    hist_v = np.zeros((steps + 1, n))
    for point in range(steps + 1):
        hist_x[point, 2 * point], hist_v[point, 2 * point + 1] = 1.0, 1.0
    hist_x, hist_v = list(hist_x), list(hist_v)
    for i in range(steps):
        t = i * dt
        x, v = hist_x[-1], hist_v[-1]
        x0, v0, x1, v1 = hist_x[0], hist_v[0], hist_x[1], hist_v[1]
        x_mid = 0.5 * (x0 + x1) + dt / 8 * (v0 - v1)  # cubic Hermite at the middle
        k1 = rhs(t, x, v, x0)
        k2 = rhs(t + dt / 2, x + dt / 2 * k1[0], v + dt / 2 * k1[1], x_mid)
        k3 = rhs(t + dt / 2, x + dt / 2 * k2[0], v + dt / 2 * k2[1], x_mid)
        k4 = rhs(t + dt, x + dt * k3[0], v + dt * k3[1], x1)
        hist_x.append(x + dt / 6 * (k1[0] + 2 * k2[0] + 2 * k3[0] + k4[0]))
        hist_v.append(v + dt / 6 * (k1[1] + 2 * k2[1] + 2 * k3[1] + k4[1]))
        hist_x.pop(0)
        hist_v.pop(0)
    mono = np.empty((n, n))
    mono[0::2], mono[1::2] = np.array(hist_x), np.array(hist_v)
    return float(np.abs(np.linalg.eigvals(mono)).max())


@pytest.mark.parametrize(
    ("arc", "rpm"),
    [(SLOT, 10000.0), (SLOT, 15000.0), (SLOT, 20000.0), (DOWN_005, 10000.0), (DOWN_005, 18000.0), (DOWN_005, 22000.0)],
)
def test_semi_discretization_against_a_second_implementation(arc, rpm):
    """The reference's boundary lies within 3 % of ours: stable at 0.97 of our critical depth,
    unstable at 1.03 of it."""
    ours = sd_critical_depths(benchmark_cut(arc), BENCHMARK, spindle_rpm=[rpm], depth_max_m=10e-3).critical_depth_m[0]
    steps = 128 if arc == SLOT else 512  # the entry's and exit's jumps in h(t) cost RK4 its order
    below, above = (reference_spectral_radius(arc, rpm, f * ours, steps) for f in (0.97, 1.03))
    assert below < 1.0 < above


def test_benchmark_values_and_the_slot_above_the_zero_order():
    """Full slot: 0.3224 mm at 10 000 rpm and 1.418 mm at 20 000 rpm (the reference's boundary,
    bisected); with two teeth in a slot the semi-discretization's lowest depth sits several
    percent above the zero-order one (the time-varying h(t), which the average drops)."""
    sd = sd_critical_depths(benchmark_cut(SLOT), BENCHMARK, spindle_rpm=[10000.0, 20000.0], depth_max_m=10e-3)
    assert sd.critical_depth_m * 1e3 == pytest.approx([0.3224, 1.418], rel=0.01)
    rpm = np.linspace(5000, 25000, 101)
    zoa = np.nanmin(zoa_critical_depths(benchmark_cut(SLOT), BENCHMARK, rpm).critical_depth_m)
    lowest = np.nanmin(
        sd_critical_depths(
            benchmark_cut(SLOT), BENCHMARK, spindle_rpm=rpm, depth_max_m=3e-3, n_depths=30
        ).critical_depth_m
    )
    assert 1.03 < lowest / zoa < 1.12


def test_flip_lobes_at_low_immersion_the_zero_order_misses():
    """a/D = 0.05 down milling: between the Hopf lobes the semi-discretization finds flip
    (period-doubling) lobes, the multiplier -1, chatter at an odd multiple of half the tooth
    frequency, well under the zero-order depth there."""
    rpm = np.array([18000.0])
    sd = sd_critical_depths(benchmark_cut(DOWN_005), BENCHMARK, spindle_rpm=rpm, depth_max_m=10e-3)
    zoa = zoa_critical_depths(benchmark_cut(DOWN_005), BENCHMARK, rpm)
    assert sd.critical_depth_m[0] < 0.5 * zoa.critical_depth_m[0]
    tooth_hz = TEETH * rpm[0] / 60
    assert (sd.chatter_hz[0] / (tooth_hz / 2)) % 2 == pytest.approx(1.0, abs=0.02)


def test_chatter_frequency_of_both_methods_agree_on_a_hopf_lobe():
    """Full slot at 10 000 rpm (a Hopf lobe): both chatter a little above the natural frequency."""
    sd = sd_critical_depths(benchmark_cut(SLOT), BENCHMARK, spindle_rpm=[10000.0], depth_max_m=10e-3)
    zoa = zoa_critical_depths(benchmark_cut(SLOT), BENCHMARK, [10000.0])
    assert sd.chatter_hz[0] == pytest.approx(zoa.chatter_hz[0], rel=0.02)
    assert F_N < zoa.chatter_hz[0] < 1.1 * F_N
