"""Metrics against closed forms, references against their definitions."""

import math

import control
import numpy as np
import pytest

from twin.metrics import contour_error, step_metrics
from twin.references import Circle, Polyline, SumOfSines, square


def test_step_metrics_second_order():
    zeta, wn = 0.3, 10.0
    sys = control.tf([wn**2], [1, 2 * zeta * wn, wn**2])
    t = np.linspace(0, 5, 50001)
    y = control.step_response(sys, T=t).outputs
    m = step_metrics(t, y, final=1.0)
    assert m["overshoot_pct"] == pytest.approx(100 * math.exp(-math.pi * zeta / math.sqrt(1 - zeta**2)), rel=1e-3)
    # first time at the final value: (pi - acos(zeta)) / wd
    wd = wn * math.sqrt(1 - zeta**2)
    assert m["rise_time_0_100_s"] == pytest.approx((math.pi - math.acos(zeta)) / wd, rel=1e-3)
    info = control.step_info(sys, T=t)
    assert m["settling_time_s"] == pytest.approx(info["SettlingTime"], rel=1e-2)
    assert m["rise_time_10_90_s"] == pytest.approx(info["RiseTime"], rel=1e-2)


def test_contour_error_of_offset_circle():
    th = np.linspace(0, 2 * np.pi, 4001)
    path = np.stack([np.cos(th), np.sin(th)], 1)
    actual = 1.01 * path[::7]
    assert contour_error(actual, path) == pytest.approx(np.full(len(actual), 0.01), abs=1e-6)


def test_circle_radius_and_feed():
    c = Circle(20.0, 2400.0)
    s = c.sample(np.linspace(0, c.period_s, 1000))
    r = np.hypot(s[:, 0, 0] + 0.02, s[:, 1, 0])
    assert r == pytest.approx(np.full(1000, 0.02))
    assert np.hypot(s[:, 0, 1], s[:, 1, 1]) == pytest.approx(np.full(1000, 0.04))  # 2400 mm/min


def test_square_and_polyline():
    sq = square(10.0, 600.0)
    assert sq.duration_s == pytest.approx(4.0)  # 40 mm at 10 mm/s
    s = sq.sample(np.array([0.5, 1.5, 4.5]))
    assert s[0, :, 0] == pytest.approx([0.005, 0.0])
    assert s[1, :, 1] == pytest.approx([0.0, 0.01])
    assert s[2, :, 1] == pytest.approx([0.0, 0.0])
    with pytest.raises(ValueError):
        Polyline([(0, 0)], 100.0)


def test_sines_derivatives():
    ref = SumOfSines((0.01,), (0.4,))
    t = np.linspace(0, 2, 20001)
    s = ref.sample(t)[:, 0]
    assert np.gradient(s[:, 0], t)[100:-100] == pytest.approx(s[100:-100, 1], abs=1e-6)
