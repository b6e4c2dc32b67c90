"""What a planner is given and hands on, whichever plans (the jerk-limited planner,
:mod:`twin.gcode.planner`, or LinuxCNC's, :mod:`twin.gcode.linuxcnc_planner`): the sample period,
the axis limits, the reference in :class:`PlanChunk` s, the program's facts gathered on the way,
the limits the reference still exceeds and how a sample is checked against them.

Units: SI (m, m/s, m/s^2, m/s^3, s).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from twin.gcode.moves import Move
from twin.gcode.path import Segment, SegmentKind

#: Planning and sampling period of the reference (s): positions are Hermite-interpolated between.
SAMPLE_PERIOD_S = 1e-3
#: A sampled value counts as over its limit beyond this ratio (floating-point noise of the
#: differences below it).
LIMIT_SLACK = 1.0 + 1e-6


@dataclass(frozen=True)
class Limits:
    """Per-axis kinematic limits (x, y, z), SI units."""

    velocity_m_per_s: tuple[float, ...]
    acceleration_m_per_s2: tuple[float, ...]
    jerk_m_per_s3: tuple[float, ...]

    def as_dict(self) -> dict:
        """Per axis, as ``twin gcode --json`` prints them."""
        return {
            axis: {
                "velocity_m_per_s": self.velocity_m_per_s[i],
                "acceleration_m_per_s2": self.acceleration_m_per_s2[i],
                "jerk_m_per_s3": self.jerk_m_per_s3[i],
            }
            for i, axis in enumerate("xyz")
        }

    def scaled(self, factor: float) -> Limits:
        """The limits a stretch of time ``factor`` (> 1: slower) keeps: velocity / k,
        acceleration / k^2, jerk / k^3."""
        return Limits(
            tuple(v / factor for v in self.velocity_m_per_s),
            tuple(a / factor**2 for a in self.acceleration_m_per_s2),
            tuple(j / factor**3 for j in self.jerk_m_per_s3),
        )


class PlanningError(ValueError):
    """A program the planner cannot turn into a bounded reference."""


class Violation(NamedTuple):
    """A limit the sampled reference exceeds after every repair: the program line, the axis,
    the quantity (``velocity``, ``acceleration``, ``jerk``) and how far over (ratio)."""

    line: int
    axis: str
    quantity: str
    ratio: float

    def as_dict(self) -> dict:
        return {"line": self.line, "axis": self.axis, "quantity": self.quantity, "ratio": round(self.ratio, 6)}

    def report_line(self) -> str:
        """The violation as the text report gives it: line, axis, quantity and the ratio (to 4
        decimals, of the JSON's 6)."""
        return f"line {self.line}, {self.axis} {self.quantity} x{round(self.ratio, 6):.4f}"


class PlanChunk(NamedTuple):
    """A stretch of the planned reference, every ``period_s`` from sample ``first``.

    Attributes
    ----------
    first : int
        Index of its first sample in the whole reference.
    position, velocity, acceleration : ndarray (n, 3)
        Machine axes x, y, z (m, m/s, m/s^2).
    line : ndarray (n,) of int
        The program line of each sample (before the filter's delay of half its window, which
        the reference leads by).
    tolerance_m : ndarray (n,)
        The tolerance in force at each sample (m; 0 under G61 / G61.1).
    """

    first: int
    position: np.ndarray
    velocity: np.ndarray
    acceleration: np.ndarray
    line: np.ndarray
    tolerance_m: np.ndarray


class ProgramFacts:
    """What the stream learns of the program as it goes (line texts, feeds, spindle, tools,
    the programmed segments, the feed-only time), gathered from the moves as they pass."""

    def __init__(self, limits: Limits):
        self.limits = limits
        self.texts: dict[int, str] = {}
        self.spindle_rpm: dict[int, float] = {}
        self.tools: dict[int, int] = {}
        self.feeds: dict[int, float] = {}
        self.feed_only_time_s = 0.0
        self.violations: list[Violation] = []
        self.notes: list[str] = []
        self.time_scale = 1.0

    def record(self, move: Move, seg: Segment | None) -> None:
        self.texts[move.line] = move.text
        self.spindle_rpm[move.line] = move.spindle_rpm if move.spindle != "off" else 0.0
        self.tools[move.line] = move.tool
        self.feeds[move.line] = move.feed_mm_per_min
        if seg is not None:
            self.feed_only_time_s += feed_only_time(seg, self.limits)


def feed_only_time(seg: Segment, limits: Limits) -> float:
    """The time (s) of a segment at its programmed feed alone (rapids at the axis limits)."""
    if seg.kind == SegmentKind.DWELL:
        return seg.dwell_s
    if seg.rapid:
        share = seg.axis_share()
        return seg.length / min(v / s for v, s in zip(limits.velocity_m_per_s, share) if s > 1e-12)
    return seg.length / seg.feed_m_per_s


def limit_ratios(velocity: np.ndarray, acceleration: np.ndarray, previous_acceleration: np.ndarray, limits: Limits):
    """Per sample and axis, the ratio of each quantity to its limit: (velocity, acceleration,
    jerk) arrays (n, 3); jerk from the acceleration before the first sample."""
    jerk = np.diff(np.concatenate([previous_acceleration[None, :], acceleration]), axis=0) / SAMPLE_PERIOD_S
    return (
        np.abs(velocity) / np.array(limits.velocity_m_per_s),
        np.abs(acceleration) / np.array(limits.acceleration_m_per_s2),
        np.abs(jerk) / np.array(limits.jerk_m_per_s3),
    )
