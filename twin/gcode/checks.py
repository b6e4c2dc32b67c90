"""Checks of a program against the machine it is planned for: the travel of its axes, and the
force its drives can deliver.

- **Travel**: every move's exact extent in machine coordinates (work offsets, G92, G52 and the
  tool length included: the reader's offsets), an arc's and a helix's from the angles where it
  passes an axis's extreme (a spiral's by bisection between samples of its turns), against each
  axis's travel. Under ``[planner] travel = "refuse"`` (the default) the first move outside is
  refused with its line (a :class:`~twin.gcode.planned.PlanningError`), under ``"warn"`` each
  line's worst excess per axis is a warning. The planned reference never leaves the
  programmed path's extent: its corner blends lie inside the corners, and the smoothing filter
  averages positions (a convex combination).
- **Drive**: on the planned reference, the drive input each axis's motion needs as a rigid body
  (:class:`DriveModel`: ``u = q0 x + q1 v + q2 a + F_c sign(v) / K``, in force ``K u = M a + B v +
  F_c sign(v)`` on a plain axis) against the drive's saturation; each line's worst sample per
  axis over it is a warning. It is what the planned motion alone needs: the controller's
  feedback asks more on top while the axis lags.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Iterator
from typing import Protocol

import numpy as np

from twin.gcode.moves import Move, MoveKind
from twin.gcode.path import Segment, SegmentKind, move_segment
from twin.gcode.planned import PlanningError
from twin.records import DriveWarning, PlanWarning, TravelWarning

#: Warnings listed at most (each check); more are counted.
MAX_WARNINGS = 100
#: How far (m) a move may pass a travel end before it is outside (the mm-to-m rounding).
TRAVEL_SLACK_M = 1e-9
#: Samples per turn of a spiral at which its extremes are bracketed.
SPIRAL_SAMPLES_PER_TURN = 64
#: Bisection steps that place a spiral's extreme (the bracket shrinks 2^-60).
BISECTION_STEPS = 60
#: How far over the saturation (ratio) a sample must be to be warned of.
DRIVE_SLACK = 1e-9


def segment_extent(seg: Segment) -> tuple[np.ndarray, np.ndarray]:
    """The lowest and highest machine coordinates (m, x y z) a segment reaches, exactly: a
    line's and a dwell's at their ends; an arc's in-plane axes also where it passes their
    extremes, a helix's normal axis at its ends (it moves linearly with the angle)."""
    low, high = np.minimum(seg.start, seg.end), np.maximum(seg.start, seg.end)
    if seg.kind != SegmentKind.ARC:
        return low, high
    assert seg.center is not None and seg.u is not None and seg.v is not None
    for axis in range(3):
        amplitude = math.hypot(seg.u[axis], seg.v[axis])
        if amplitude < 1e-12:
            continue  # the normal axis
        # the axis's offset from the centre: r(t) (u_j cos t + v_j sin t) = r(t) A cos(t - phase)
        phase = math.atan2(seg.v[axis], seg.u[axis])
        for value in _turning_offsets(seg, amplitude, phase):
            low[axis] = min(low[axis], seg.center[axis] + value)
            high[axis] = max(high[axis], seg.center[axis] + value)
    return low, high


def _turning_offsets(seg: Segment, amplitude: float, phase: float) -> list[float]:
    """An in-plane axis's offsets (m) from the arc's centre where the arc ``seg`` turns along it,
    inside its sweep: the extremes of ``r(t) A cos(t - phase)``, ``r(t) = r0 + k t``."""
    k = (seg.radius_end - seg.radius) / seg.sweep
    if k == 0.0:  # a circle or a helix: at t = phase + m pi, the top for m even, the bottom odd
        first = math.ceil(-phase / math.pi)
        last = math.floor((seg.sweep - phase) / math.pi)
        return [seg.radius * amplitude * (-1.0) ** m for m in range(first, min(last, first + 1) + 1)]

    # a spiral: where the slope k cos(t - phase) - r(t) sin(t - phase) changes sign, bracketed
    # between samples of its turns and bisected
    def slope(t: np.ndarray) -> np.ndarray:
        return k * np.cos(t - phase) - (seg.radius + k * t) * np.sin(t - phase)

    t = np.linspace(0.0, seg.sweep, max(2, math.ceil(seg.sweep / (2 * math.pi) * SPIRAL_SAMPLES_PER_TURN)) + 1)
    g = slope(t)
    where = np.nonzero(np.sign(g[:-1]) * np.sign(g[1:]) < 0)[0]
    lo, hi, g_lo = t[where], t[where + 1], g[where]
    for _ in range(BISECTION_STEPS):
        mid = 0.5 * (lo + hi)
        g_mid = slope(mid)
        same = np.sign(g_mid) == np.sign(g_lo)
        lo, hi, g_lo = np.where(same, mid, lo), np.where(same, hi, mid), np.where(same, g_mid, g_lo)
    turns = np.concatenate([0.5 * (lo + hi), t[g == 0.0]])
    return ((seg.radius + k * turns) * amplitude * np.cos(turns - phase)).tolist()


class Warnings:
    """One check's warnings, the worst of each line and axis, the first :data:`MAX_WARNINGS`
    (line, axis) pairs listed and every one counted.

    Attributes
    ----------
    kept : dict
        ``{(line, axis): (warning, badness)}``: the pair's worst warning so far and how bad it is
        (the check's ranking: m outside the travel, ratio to the saturation).
    warned : set of (int, str)
        Every (line, axis) pair warned of, listed or not.
    """

    def __init__(self) -> None:
        self.kept: dict[tuple[int, str], tuple[PlanWarning, float]] = {}
        self.warned: set[tuple[int, str]] = set()  # a pair per program line at most, as its text

    @property
    def total(self) -> int:
        """Every (line, axis) pair warned of, listed or not."""
        return len(self.warned)

    def add(self, warning: PlanWarning, badness: float) -> None:
        """Keep ``warning`` if it is its line and axis's first or worst (by ``badness``)."""
        key = (warning.line, warning.axis)
        self.warned.add(key)
        held = self.kept.get(key)
        if (held is None and len(self.kept) < MAX_WARNINGS) or (held is not None and badness > held[1]):
            self.kept[key] = (warning, badness)

    def listed(self) -> list[PlanWarning]:
        """The warnings kept, by line and axis."""
        return [warning for _key, (warning, _badness) in sorted(self.kept.items())]


class TravelCheck:
    """Each move against the axes' travel (see the module's docstring).

    Parameters
    ----------
    travel_m : dict of int to (float, float)
        Per axis index (0 x, 1 y, 2 z) with a travel, its lowest and highest machine coordinate
        (m); an axis without one is not checked.
    refuse : bool
        Refuse the first move outside (else warn of each).
    """

    def __init__(self, travel_m: dict[int, tuple[float, float]], refuse: bool) -> None:
        self.travel_m = travel_m
        self.refuse = refuse
        self.warnings = Warnings()

    def passing(self, moves: Iterable[Move]) -> Iterator[Move]:
        """``moves`` as they pass, each checked (from the previous one's end, as the planner
        strings them).

        Raises
        ------
        PlanningError
            With ``refuse``: the first move outside, its line, the coordinate and the travel.
        """
        if not self.travel_m:
            yield from moves  # a machine without travel: nothing to check
            return
        position = None
        for move in moves:
            if position is None:
                position = (np.asarray(move.start_mm) + np.asarray(move.offset_mm)) * 1e-3
                self._check(move, position, position)
            if move.kind in (MoveKind.RAPID, MoveKind.FEED):  # a line: its ends (what move_segment makes of it)
                end = (np.asarray(move.end_mm) + np.asarray(move.offset_mm)) * 1e-3
                self._check(move, np.minimum(position, end), np.maximum(position, end))
                position = end
            elif move.kind == MoveKind.ARC:
                seg = move_segment(move, position, 0.0)
                if seg is not None:
                    self._check(move, *segment_extent(seg))
                    position = seg.end
            yield move

    def check(self, moves: Iterable[Move]) -> None:
        """Check every move of ``moves`` (see :meth:`passing`)."""
        for _move in self.passing(moves):
            pass

    def _check(self, move: Move, low: np.ndarray, high: np.ndarray) -> None:
        for axis, (first, last) in self.travel_m.items():
            below, above = first - float(low[axis]), float(high[axis]) - last
            if below <= TRAVEL_SLACK_M and above <= TRAVEL_SLACK_M:
                continue
            value = low[axis] if below >= above else high[axis]
            name = "xyz"[axis]
            message = (
                f"{name.upper()} {value * 1e3:.3f} mm (machine coordinates) is outside the travel "
                f"{first * 1e3:.3f}..{last * 1e3:.3f} mm of axis {name}"
            )
            if self.refuse:
                raise PlanningError(f'line {move.line}: {message} (travel = "warn" in [planner] to warn only)')
            warning = TravelWarning(
                line=move.line, axis=name, value_mm=round(value * 1e3, 6), message=message, text=move.text
            )
            self.warnings.add(warning, max(below, above))


class DriveModel(Protocol):
    """What the drive check needs of an axis's drive (:class:`twin.machines.rigid_drive.RigidDrive`)."""

    @property
    def volts_per_m(self) -> float: ...

    @property
    def volts_per_m_per_s(self) -> float: ...

    @property
    def volts_per_m_per_s2(self) -> float: ...

    @property
    def force_per_volt_N_per_V(self) -> float: ...

    @property
    def coulomb_N(self) -> float: ...


def drive_volts(drive: DriveModel, position: np.ndarray, velocity: np.ndarray, acceleration: np.ndarray) -> np.ndarray:
    """The drive input (V) an axis's motion needs as a rigid body: ``q0 x + q1 v + q2 a + F_c
    sign(v) / K`` at each sample (m, m/s, m/s^2)."""
    return (
        drive.volts_per_m * position
        + drive.volts_per_m_per_s * velocity
        + drive.volts_per_m_per_s2 * acceleration
        + drive.coulomb_N / drive.force_per_volt_N_per_V * np.sign(velocity)
    )


class DriveCheck:
    """The planned reference against each axis's drive (see the module's docstring); fed the
    reference in pieces as it is planned (:meth:`add`).

    Parameters
    ----------
    drives : dict of int to DriveModel
        Per axis index (0 x, 1 y) the machine drives.
    saturation_V : float
        The drive's saturation (V), every axis's.
    """

    def __init__(self, drives: dict[int, DriveModel], saturation_V: float) -> None:
        self.drives = drives
        self.saturation_V = saturation_V
        self.warnings = Warnings()

    def add(
        self, position: np.ndarray, velocity: np.ndarray, acceleration: np.ndarray, line: np.ndarray, texts: dict
    ) -> None:
        """Check a stretch of the reference: samples (n, 3) of x y z (m, m/s, m/s^2), the line
        of each, and the lines' texts."""
        for axis, drive in self.drives.items():
            ratio = np.abs(drive_volts(drive, position[:, axis], velocity[:, axis], acceleration[:, axis]))
            ratio /= self.saturation_V
            over = np.nonzero(ratio > 1.0 + DRIVE_SLACK)[0]
            if over.size == 0:
                continue
            # the worst sample of each line
            order = np.lexsort((-ratio[over], line[over]))
            lines, first = np.unique(line[over][order], return_index=True)
            for number, k in zip(lines.tolist(), over[order][first].tolist()):
                self._warn(int(number), "xyz"[axis], float(ratio[k]), drive, texts)

    def _warn(self, line: int, axis: str, ratio: float, drive: DriveModel, texts: dict) -> None:
        limit_N = drive.force_per_volt_N_per_V * self.saturation_V
        message = f"axis {axis} needs {ratio * limit_N:.1f} N, the drive saturates at {limit_N:.1f} N (x{ratio:.3f})"
        warning = DriveWarning(
            line=line,
            axis=axis,
            ratio=round(ratio, 6),
            force_N=round(ratio * limit_N, 3),
            message=message,
            text=texts.get(line, ""),
        )
        self.warnings.add(warning, ratio)


def plan_warnings(*checks: TravelCheck | DriveCheck | None) -> tuple[list[PlanWarning], int]:
    """The warnings of ``checks`` (None: a check not run) by line, check and axis, and how many
    in all."""
    done = [c.warnings for c in checks if c is not None]
    listed = sorted((w for found in done for w in found.listed()), key=lambda w: (w.line, w.check, w.axis))
    return listed, sum(found.total for found in done)
