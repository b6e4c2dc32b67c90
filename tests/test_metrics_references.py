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


def _brute_contour_error(actual, path):
    """Distance to every segment of the path, the minimum taken: O(n m), the reference."""
    a, b = path[:-1], path[1:]
    ab = b - a
    s = np.clip(((actual[:, None] - a) * ab).sum(-1) / np.maximum((ab**2).sum(1), 1e-300), 0.0, 1.0)
    return np.linalg.norm(actual[:, None] - (a + s[..., None] * ab), axis=-1).min(axis=1)


@pytest.mark.parametrize("stride", [1, 5, 40])
def test_contour_error_follows_the_path_and_equals_the_full_search(stride):
    """An open spiral with a square corner, tracked with lag and noise: the windowed O(n)
    search equals the distance to every segment (the path never comes back near itself)."""
    t = np.linspace(0.0, 6.0, 3000)
    r = 0.01 + 0.004 * t
    path = np.stack([r * np.cos(t), r * np.sin(t)], 1)
    path = np.vstack([path, path[-1] + np.outer(np.linspace(0, 0.02, 300)[1:], [0.0, 1.0])])
    rng = np.random.default_rng(4)
    lagged = np.vstack([np.repeat(path[:1], 12, axis=0), path[:-12]])  # 12 samples behind
    actual = lagged[::stride] + rng.normal(scale=2e-5, size=lagged[::stride].shape)
    np.testing.assert_allclose(contour_error(actual, path), _brute_contour_error(actual, path), rtol=0, atol=1e-15)


def test_contour_error_where_the_path_turns_back_over_itself():
    """A line cut out and back and out again, further (step-downs over one XY path): leg A
    X 0 -> 10 mm, leg B back at Y +2 µm, leg C X 0 -> 20 mm at Y 0, the tool on leg C at Y +5 µm
    and 20 samples behind.  Leg B is nearer the tool than its own leg; the walk must still not
    follow it backwards and lose the tool where leg C goes on past X 10: there the error is the
    tool's 5 µm from leg C."""
    a = np.linspace(0.0, 10.0, 2001)
    c = np.linspace(0.0, 20.0, 4001)
    x = np.concatenate([a, a[::-1][1:], c[1:]])
    y = np.concatenate([np.zeros(2001), np.full(2000, 2e-3), np.zeros(4000)])
    path = np.column_stack([x, y]) * 1e-3
    on_c = np.arange(4001, len(x))
    tool = np.column_stack([x[on_c - 20], np.full(len(on_c), 5e-3)]) * 1e-3
    ce = contour_error(np.vstack([path[:4001], tool]), path)[4001:]
    past_a = x[on_c - 20] > 10.5
    assert past_a.sum() > 1500
    np.testing.assert_allclose(ce[past_a], 5e-6, atol=1e-12)


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
