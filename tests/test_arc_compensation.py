"""Arcs at the machine's speed (issue 46): the moving-average filter's shrink of an arc
compensated, so that circles run at the jerk-limited optimum ``min(F, sqrt(a R), (j R^2)^(1/3))``
with the path tolerance held; straight moves against the closed-form time-optimal jerk-limited
profile, written here independently of the planner."""

import math

import numpy as np
import pytest

from twin.gcode.planned import Limits
from twin.gcode.planner import PlannerSettings, plan
from twin.gcode.reader import Reader
from twin.machines import build

LINEAR_MOTOR = PlannerSettings().limits(build("linear_motor_xy").motion_limits)
GOOGOL = PlannerSettings().limits(build("googol_xy").motion_limits)


def _circles(radius_mm: float, turns: int, tolerance_mm: float = 0.01) -> list[str]:
    """A line to the circle's left end, then ``turns`` tangent full circles at F60000 (the
    issue's test1.ngc, shorter)."""
    r = radius_mm
    return [f"G21 G90 G17 G64 P{tolerance_mm}", "G0 X0 Y0", f"G1 X{r} F3000"] + [f"G2 X{r} Y0 I{r} J0 F60000"] * turns


def _optimum(radius_m: float, feed_m_per_s: float, limits: Limits) -> float:
    """The jerk-limited speed on a circle in X/Y: min(F, v_axis, sqrt(a R), (j R^2)^(1/3)) with
    the smaller axis's a and j."""
    a = min(limits.acceleration_m_per_s2[:2])
    j = min(limits.jerk_m_per_s3[:2])
    v = min(limits.velocity_m_per_s[:2])
    return min(feed_m_per_s, v, math.sqrt(a * radius_m), (j * radius_m**2) ** (1 / 3))


def _distance_to_circles_and_line(position: np.ndarray, radius_m: float) -> np.ndarray:
    """The exact distance of each sample to the programmed path of :func:`_circles`: the line
    from the origin to (R, 0) and the circle about (2R, 0)."""
    x, y = position[:, 0], position[:, 1]
    to_circle = np.abs(np.hypot(x - 2 * radius_m, y) - radius_m)
    along = np.clip(x / radius_m, 0.0, 1.0) * radius_m
    to_line = np.hypot(x - along, y)
    return np.minimum(to_circle, to_line)


@pytest.mark.parametrize("radius_mm", [1.0, 5.0, 20.0, 50.0])
def test_a_circle_runs_within_5_percent_of_the_jerk_limited_optimum(radius_mm):
    """linear_motor_xy, F60000, tolerance 0.01 mm: the middle turn's speed within 5 % of the
    optimum (before compensation R 5 mm ran at 77 mm/s against 306), and the path within the
    tolerance everywhere (the exact distance to the line and the circle)."""
    r = radius_mm * 1e-3
    p = plan(Reader(_circles(radius_mm, 3)).moves(), LINEAR_MOTOR, PlannerSettings())
    speed = np.hypot(p.velocity[:, 0], p.velocity[:, 1])
    optimum = _optimum(r, 1.0, LINEAR_MOTOR)
    middle = speed[(p.line == 5)]
    assert middle.min() >= 0.95 * optimum
    assert middle.max() <= optimum * 1.000001
    assert not p.violations
    assert _distance_to_circles_and_line(p.position, r).max() <= 1e-5


def test_the_issues_circles_take_about_the_optimums_time():
    """test1.ngc on linear_motor_xy: 20 circles of R 5 mm (2.08 s at the optimum, 8.14 s before)."""
    p = plan(Reader(_circles(5.0, 20)).moves(), LINEAR_MOTOR, PlannerSettings())
    circles_s = 20 * 2 * math.pi * 5e-3 / _optimum(5e-3, 1.0, LINEAR_MOTOR)
    assert circles_s < p.cycle_time_s < circles_s + 1.2  # the 5 mm line at 50 mm/s (0.1 s), the ramps


@pytest.mark.parametrize("tolerance_mm", [0.002, 0.01, 0.05])
def test_small_arcs_between_lines_keep_the_tolerance_and_the_limits(tolerance_mm):
    """Half circles of R 0.5 mm joining 2 mm lines (a raster), tangent, where the speed rises
    and falls within each arc: the compensation follows it within the tolerance (the exact
    distance to every line and arc), and every axis stays within its limits."""
    lines, y = [f"G21 G90 G17 G64 P{tolerance_mm}", "G0 X0 Y0", "F3000"], 0.0
    for k in range(8):
        end_x = 2.0 if k % 2 == 0 else 0.0
        lines += [f"G1 X{end_x}", f"G{3 if k % 2 == 0 else 2} X{end_x} Y{y + 1:g} I0 J0.5"]
        y += 1.0
    for limits in (LINEAR_MOTOR, GOOGOL):
        p = plan(Reader(lines).moves(), limits, PlannerSettings())
        x, yy = p.position[:, 0] * 1e3, p.position[:, 1] * 1e3
        rows = np.rint(yy - 0.5)
        centre_x = np.where(rows % 2 == 0, 2.0, 0.0)
        beyond = np.where(centre_x > 0, x > 2.0, x < 0.0)
        to_arc = np.abs(np.hypot(x - centre_x, yy - (rows + 0.5)) - 0.5)
        to_line = np.min(np.abs(yy[:, None] - np.arange(0.0, 9.0)[None, :]), axis=1)
        distance = np.where(beyond, to_arc, np.minimum(to_line, to_arc))
        assert distance.max() <= tolerance_mm
        assert not p.violations
        jerk = np.diff(p.acceleration, axis=0) / p.period_s
        assert (np.abs(jerk).max(axis=0) <= np.array(limits.jerk_m_per_s3) * 1.000001).all()


def _time_optimal_s(length: float, v: float, a: float, j: float) -> float:
    """The rest-to-rest time of the time-optimal jerk-limited profile (closed form): with
    cruise, acceleration reached or not; without cruise, acceleration reached
    (``L >= 2 a^3 / j^2``) or not (``4 (L / 2j)^(1/3)``)."""
    to_speed = v / a + a / j if v >= a * a / j else 2.0 * math.sqrt(v / j)
    if length >= v * to_speed:
        return length / v + to_speed
    if length >= 2.0 * a**3 / j**2:
        peak = 0.5 * a * (-a / j + math.sqrt((a / j) ** 2 + 4.0 * length / a))
        return 2.0 * (peak / a + a / j)
    return 4.0 * (length / (2.0 * j)) ** (1.0 / 3.0)


def _fixed_filter_s(length: float, v: float, a: float, t_filter: float) -> float:
    """The time of a trapezoidal profile (acceleration a, with at least a cruise of T at its
    peak) through a moving average of fixed length T: ``L / v + v / a + T`` with a cruise, else
    ``2 v_p / a + 2 T`` with ``L = v_p (v_p / a + T)``."""
    if length >= v * (v / a + t_filter):
        return length / v + v / a + t_filter
    peak = 0.5 * a * (-t_filter + math.sqrt(t_filter**2 + 4.0 * length / a))
    return 2.0 * peak / a + 2.0 * t_filter


def _motion_s(p) -> float:
    """The time from the last sample at the start to the first at the end."""
    x = p.position[:, 0]
    left = int(np.nonzero(x == x[0])[0].max())
    arrived = int(np.nonzero(x == x[-1])[0].min())
    return (arrived - left) * p.period_s


@pytest.mark.parametrize("machine", ["linear_motor_xy", "googol_xy"])
@pytest.mark.parametrize("length_mm", [1.0, 2.0, 4.0, 8.0, 20.0, 50.0, 200.0])
@pytest.mark.parametrize("feed", [3000.0, 60000.0])
def test_a_straight_move_takes_the_time_optimal_time_where_a_fixed_filter_can(machine, length_mm, feed):
    """Every move within a sample period or two (the sampled ends) of the trapezoid through the
    filter of fixed length T = a / j; that is the time-optimal jerk-limited profile (closed form)
    where the optimum reaches the acceleration limit (v >= a^2 / j and L >= 2 a^3 / j^2), and
    within 1 % of it wherever the move takes 0.2 s or more. Below those, the optimum's jerk
    phases are shorter than T: up to 30 % longer here (a limit of this design, documented).
    (Under 1 mm the peak's cap, found between grid points, adds a few ms more.)"""
    limits = PlannerSettings().limits(build(machine).motion_limits)
    p = plan(Reader(["G21 G90 G0 X0 Y0", f"G1 X{length_mm} F{feed}"]).moves(), limits, PlannerSettings())
    v = min(feed / 60e3, limits.velocity_m_per_s[0])
    a, j = limits.acceleration_m_per_s2[0], limits.jerk_m_per_s3[0]
    length = length_mm * 1e-3
    optimum = _time_optimal_s(length, v, a, j)
    fixed = _fixed_filter_s(length, v, a, p.filter_s)
    assert fixed - p.period_s <= _motion_s(p) <= fixed + 2 * p.period_s
    assert p.filter_s == pytest.approx(a / j, rel=1e-9)
    if v >= a * a / j and length >= 2 * a**3 / j**2:
        assert fixed == pytest.approx(optimum, rel=1e-9)
    assert optimum - 1e-9 <= fixed < 1.3 * optimum
    if optimum >= 0.2:
        assert _motion_s(p) <= 1.01 * optimum


@pytest.mark.parametrize("radius_mm, rise_mm, end_off_mm", [(2.0, -1.0, 0.0), (3.0, 0.0, 0.004)])
def test_a_helix_and_a_spiral_keep_the_tolerance(radius_mm, rise_mm, end_off_mm):
    """Two turns of a helix (the compensation in the plane of the turn, the rise untouched)
    and of a spiral (an end 4 um off the circle, moved as LinuxCNC moves it), at F60000 on
    linear_motor_xy: every sample within the tolerance of the programmed curve, measured by
    brute force against 1 um points of it, and within the limits."""
    r, tolerance = radius_mm * 1e-3, 1e-5
    lines = ["G21 G90 G17 G64 P0.01", "G0 X0 Y0 Z0", f"G2 X{end_off_mm} Y0 Z{rise_mm} I{radius_mm} J0 P2 F60000"]
    p = plan(Reader(lines).moves(), LINEAR_MOTOR, PlannerSettings())
    assert not p.violations
    speed = np.linalg.norm(p.velocity, axis=1)
    assert speed.max() >= 0.95 * _optimum(r, 1.0, LINEAR_MOTOR)
    # the programmed curve: from the angle pi (the start, left of the centre), clockwise, the
    # radius linear in the angle from R to the end's R - off, the rise linear in it
    phi = np.linspace(0.0, 4 * math.pi, int(4 * math.pi * r / 1e-6))
    radius = r - end_off_mm * 1e-3 * phi / (4 * math.pi)
    curve = np.stack(
        [r + radius * np.cos(math.pi - phi), radius * np.sin(math.pi - phi), rise_mm * 1e-3 * phi / (4 * math.pi)],
        axis=1,
    )
    nearest = np.full(len(p.position), np.inf)
    for lo in range(0, len(curve), 4000):
        d = np.linalg.norm(p.position[:, None, :] - curve[None, lo : lo + 4000, :], axis=2)
        nearest = np.minimum(nearest, d.min(axis=1))
    assert nearest.max() <= tolerance * 1.01  # the 1 um points' chord
