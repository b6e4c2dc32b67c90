"""Typed records of a program's run: its per-line rows, its warnings and its part's inspected
features.  Each is frozen; ``to_json()`` gives what ``twin run --json`` prints for it (key for
key, in that order), and the command line prints them through their attributes and methods.

- :class:`LineRow`: a program line's row of the per-line table (``lines``);
- :class:`MachiningWarning` (``machining_warnings``), :class:`TravelWarning` and
  :class:`DriveWarning` (``plan_warnings``), :class:`ChatterWarning` (``chatter_warnings``):
  each with ``line`` (None: the whole run), ``message`` and the line's ``text``;
- :class:`ChatterCheck`: a line's or the run's chatter (``chatter``);
- :class:`LineStability`: a cutting line's check against the tool's lobes (a row's ``stability``);
- :class:`CircleMeasured`, :class:`LineMeasured`, :class:`WidthMeasured` and
  :class:`FeatureNotFound` (``inspection``), of the feature types of :class:`FeatureType`.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass
from enum import StrEnum
from typing import Any, ClassVar, Literal


class FeatureType(StrEnum):
    """An ``[[inspect]]`` feature's ``type``: what it measures (:mod:`twin.machining.inspection`)."""

    #: A bore or boss: the least-squares circle's diameter, centre and roundness.
    CIRCLE = "circle"
    #: A straight wall: the least-squares line's position and straightness.
    LINE = "line"
    #: A slot's or pocket's width: the two-point size across it.
    WIDTH = "width"


def _verdict(passed: bool | None) -> str:
    """A verdict as the text report ends a feature's line: nothing without a tolerance."""
    return "" if passed is None else ("  pass" if passed else "  FAIL")


def _label_verdict(passed: bool | None) -> str:
    return "" if passed is None else (" pass" if passed else " FAIL")


@dataclass(frozen=True)
class FeatureNotFound:
    """A feature that could not be measured, and why (``message``); it never passes."""

    name: str
    type: FeatureType
    z_mm: float
    message: str

    def to_json(self) -> dict[str, Any]:
        """``name``, ``type``, ``z_mm``, ``found`` (False), ``message``, ``pass`` (False)."""
        return {
            "name": self.name,
            "type": self.type.value,
            "z_mm": self.z_mm,
            "found": False,
            "message": self.message,
            "pass": False,
        }

    @property
    def place_mm(self) -> None:
        """Nowhere: nothing was measured."""
        return None

    def report_line(self) -> str:
        """The feature's line in the text report."""
        return f"{self.name:<20} {self.type.value:<7} not found: {self.message}"

    def label(self) -> str:
        """The feature's label on the plots and the recording."""
        return f"{self.name}: not found"


@dataclass(frozen=True, kw_only=True)
class _Measured(ABC):
    """What every measured feature has: its name, height (mm), deviation (µm, measured less
    nominal) and verdict (``passed``: within ``tolerance_um``; None: no tolerance)."""

    type: ClassVar[FeatureType]
    name: str
    z_mm: float
    deviation_um: float
    passed: bool | None

    @abstractmethod
    def _sizes(self) -> dict[str, Any]:
        """The type's own measured values, as the JSON gives them."""

    def to_json(self) -> dict[str, Any]:
        """``name``, ``type``, ``z_mm``, the type's measured values, ``deviation_um``, ``pass``."""
        return {
            "name": self.name,
            "type": self.type.value,
            "z_mm": self.z_mm,
            **self._sizes(),
            "deviation_um": self.deviation_um,
            "pass": self.passed,
        }

    @abstractmethod
    def measured_text(self) -> str:
        """The measured size or position as the text report gives it."""

    @property
    def form_um(self) -> float | None:
        """The form error (µm: roundness, straightness); None: the type has none."""
        return None

    def report_line(self) -> str:
        """The feature's line in the text report: measured, deviation, form and verdict."""
        form = "" if self.form_um is None else f"  form {self.form_um:.3f} µm"
        return (
            f"{self.name:<20} {self.type.value:<7} {self.measured_text()}  deviation {self.deviation_um:+.3f} µm"
            f"{form}{_verdict(self.passed)}"
        )

    def label(self) -> str:
        """The feature's label on the plots and the recording."""
        return f"{self.name}: {self.deviation_um:+.1f} µm{_label_verdict(self.passed)}"


@dataclass(frozen=True, kw_only=True)
class CircleMeasured(_Measured):
    """A circle's least-squares diameter (mm), centre [x, y] (mm) and roundness (µm, peak to
    valley of the radial residuals)."""

    type: ClassVar[FeatureType] = FeatureType.CIRCLE
    diameter_mm: float
    center_mm: tuple[float, float]
    roundness_um: float

    def _sizes(self) -> dict[str, Any]:
        return {"diameter_mm": self.diameter_mm, "center_mm": list(self.center_mm), "roundness_um": self.roundness_um}

    def measured_text(self) -> str:
        return f"{self.diameter_mm:.4f} mm"

    @property
    def form_um(self) -> float:
        return self.roundness_um

    @property
    def place_mm(self) -> tuple[float, float]:
        """Where the feature is labelled: its centre [x, y] (mm)."""
        return self.center_mm


@dataclass(frozen=True, kw_only=True)
class LineMeasured(_Measured):
    """A wall's least-squares line: its position [x, y] (mm) where the nominal line's middle falls
    on it, and its straightness (µm, peak to valley)."""

    type: ClassVar[FeatureType] = FeatureType.LINE
    position_mm: tuple[float, float]
    straightness_um: float

    def _sizes(self) -> dict[str, Any]:
        return {"position_mm": list(self.position_mm), "straightness_um": self.straightness_um}

    def measured_text(self) -> str:
        return f"at {self.position_mm[0]:.4f}, {self.position_mm[1]:.4f} mm"

    @property
    def form_um(self) -> float:
        return self.straightness_um

    @property
    def place_mm(self) -> tuple[float, float]:
        """Where the feature is labelled: its position [x, y] (mm)."""
        return self.position_mm


@dataclass(frozen=True, kw_only=True)
class WidthMeasured(_Measured):
    """A slot's or pocket's two-point width (mm) and the middle [x, y] (mm) of the gap."""

    type: ClassVar[FeatureType] = FeatureType.WIDTH
    width_mm: float
    center_mm: tuple[float, float]

    def _sizes(self) -> dict[str, Any]:
        return {"width_mm": self.width_mm, "center_mm": list(self.center_mm)}

    def measured_text(self) -> str:
        return f"{self.width_mm:.4f} mm"

    @property
    def place_mm(self) -> tuple[float, float]:
        """Where the feature is labelled: the gap's middle [x, y] (mm)."""
        return self.center_mm


#: A feature's inspection: measured (of its type), or not found.
Inspected = CircleMeasured | LineMeasured | WidthMeasured | FeatureNotFound


@dataclass(frozen=True)
class MachiningWarning:
    """A crash or misuse on a program line (:func:`twin.machining.misuse.machining_warnings`): its
    ``kind``, the worst ``value`` on the line in ``unit`` and the ``message`` that says it."""

    line: int
    text: str
    kind: str
    value: float
    unit: str
    message: str

    def to_json(self) -> dict[str, Any]:
        """``line``, ``text``, ``kind``, ``value``, ``unit``, ``message``."""
        return {
            "line": self.line,
            "text": self.text,
            "kind": self.kind,
            "value": self.value,
            "unit": self.unit,
            "message": self.message,
        }


@dataclass(frozen=True)
class TravelWarning:
    """A move outside an axis's travel (:class:`twin.gcode.checks.TravelCheck`): the furthest
    ``value_mm`` (machine coordinates) on ``axis``."""

    check: ClassVar[Literal["travel"]] = "travel"
    line: int
    axis: str
    value_mm: float
    message: str
    text: str

    def to_json(self) -> dict[str, Any]:
        """``line``, ``check`` ("travel"), ``axis``, ``value_mm``, ``message``, ``text``."""
        return {
            "line": self.line,
            "check": self.check,
            "axis": self.axis,
            "value_mm": self.value_mm,
            "message": self.message,
            "text": self.text,
        }


@dataclass(frozen=True)
class DriveWarning:
    """A line whose motion needs more than ``axis``'s drive delivers
    (:class:`twin.gcode.checks.DriveCheck`): the worst ``ratio`` to the saturation and the force
    (N) it needs."""

    check: ClassVar[Literal["drive"]] = "drive"
    line: int
    axis: str
    ratio: float
    force_N: float
    message: str
    text: str

    def to_json(self) -> dict[str, Any]:
        """``line``, ``check`` ("drive"), ``axis``, ``ratio``, ``force_N``, ``message``, ``text``."""
        return {
            "line": self.line,
            "check": self.check,
            "axis": self.axis,
            "ratio": self.ratio,
            "force_N": self.force_N,
            "message": self.message,
            "text": self.text,
        }


#: A warning against the machine.
PlanWarning = TravelWarning | DriveWarning


@dataclass(frozen=True)
class ChatterWarning:
    """A program line that chatters, or the whole run (``line`` None, ``text`` empty)."""

    line: int | None
    message: str
    text: str

    def to_json(self) -> dict[str, Any]:
        """``line``, ``message``, ``text``."""
        return {"line": self.line, "message": self.message, "text": self.text}


#: Any warning of a run: each has ``line`` (None: the run), ``message`` and ``text``.
LineWarning = MachiningWarning | TravelWarning | DriveWarning | ChatterWarning


@dataclass(frozen=True)
class ChatterCheck:
    """The chatter of a stretch of a run (a program line, or the whole run) as it is reported
    (:meth:`twin.machining.chatter.ChatterReading.check`): the ``indicator`` (to 4 decimals),
    whether it is over the ``threshold`` (``chatters``), the frequency (Hz, to 0.1; None where it
    does not chatter) and the ``windows`` read."""

    indicator: float
    chatters: bool
    chatter_hz: float | None
    threshold: float
    windows: int

    def to_json(self) -> dict[str, Any]:
        """``indicator``, ``chatter`` (the verdict), ``chatter_hz``, ``threshold``, ``windows``."""
        return {
            "indicator": self.indicator,
            "chatter": self.chatters,
            "chatter_hz": self.chatter_hz,
            "threshold": self.threshold,
            "windows": self.windows,
        }

    def to_columns(self) -> dict[str, Any]:
        """The check as the per-line table's columns: ``chatter_indicator``, ``chatter``,
        ``chatter_hz``, ``chatter_threshold``, ``chatter_windows``."""
        return {
            "chatter_indicator": self.indicator,
            "chatter": self.chatters,
            "chatter_hz": self.chatter_hz,
            "chatter_threshold": self.threshold,
            "chatter_windows": self.windows,
        }

    def report_line(self) -> str:
        """The run's chatter line in the text summary: indicator, verdict, frequency."""
        verdict = f"over {self.threshold}: chatters" if self.chatters else f"under {self.threshold}: stable"
        hz = "" if self.chatter_hz is None else f" at {self.chatter_hz:.1f} Hz"
        return f"{'chatter':<28} indicator {self.indicator:.3f} {verdict}{hz}"


@dataclass(frozen=True)
class LineStability:
    """A cutting program line checked against the tool's zero-order lobes at its sample of least
    margin (:func:`twin.machining.program_stability.line_stability`).

    Attributes
    ----------
    depth_mm : float
        The line's axial depth (mm, to 4 decimals).
    spindle_rpm : float
        Its spindle speed (rpm, to 0.1).
    critical_depth_mm : float or None
        The critical depth at that speed (mm, to 4 decimals); None: no boundary.
    margin : float or None
        Critical over actual depth (to 3 decimals); None: no boundary.
    chatter_hz : float or None
        The chatter frequency at the boundary (Hz, to 0.1); None: no boundary.
    stable_rpm : (float, float) or None
        The stretch of stable speeds (rpm, to 10) holding the line's speed or nearest it; None:
        none in the range searched.
    text : str
        The one line a user reads ("line 57: 4.00 mm at 12 000 rpm, critical 2.10 mm; ...").
    """

    depth_mm: float
    spindle_rpm: float
    critical_depth_mm: float | None
    margin: float | None
    chatter_hz: float | None
    stable_rpm: tuple[float, float] | None
    text: str

    @property
    def over_critical(self) -> bool:
        """Whether the line cuts deeper than its critical depth (margin under 1)."""
        return self.margin is not None and self.margin < 1

    def _values(self) -> dict[str, Any]:
        """The attributes but ``stable_rpm``, in their order."""
        return {
            "depth_mm": self.depth_mm,
            "spindle_rpm": self.spindle_rpm,
            "critical_depth_mm": self.critical_depth_mm,
            "margin": self.margin,
            "chatter_hz": self.chatter_hz,
        }

    def to_json(self) -> dict[str, Any]:
        """The attributes in their order, ``stable_rpm`` as [low, high] (or None)."""
        stable = None if self.stable_rpm is None else list(self.stable_rpm)
        return {**self._values(), "stable_rpm": stable, "text": self.text}

    @classmethod
    def from_json(cls, values: dict[str, Any]) -> LineStability:
        """The check from its :meth:`to_json` (``twin lobes``' summary holds it so)."""
        stable = values["stable_rpm"]
        return cls(**{**values, "stable_rpm": None if stable is None else tuple(stable)})

    def to_columns(self) -> dict[str, Any]:
        """The check as the per-line table's columns: ``stability_<attribute>``, ``stable_rpm``
        as ``stability_stable_rpm_low`` and ``_high`` (None: no stable speed) after ``text``."""
        low, high = self.stable_rpm or (None, None)
        out = {f"stability_{key}": value for key, value in self._values().items()}
        return out | {
            "stability_text": self.text,
            "stability_stable_rpm_low": low,
            "stability_stable_rpm_high": high,
        }


@dataclass(frozen=True)
class LineRow:
    """A program line's row of the per-line table, over the recorded ticks the reference is on it.

    Attributes
    ----------
    line : int
    text : str
    t_start_s, t_end_s : float
        The line's span (s).
    max_tracking_error_um : dict of str to float
        Per axis (µm).
    max_cutting_force_N : float
        The largest XY cutting force (N).
    max_contour_error_um, rms_contour_error_um : float or None
        None: the path is not 2-D.
    mean_engagement_deg, axial_depth_mm : float or None
        With a stock: the mean engaged angle (deg) and the largest axial depth (mm).
    max_wall_error_um : float or None
        With a stock: the largest wall error the line left (µm).
    stability : LineStability or None
        A cutting line's check against the tool's lobes; None: the line does not cut with a tool
        that has dynamics.
    chatter : ChatterCheck or None
        The line's chatter in the run; None: the tool did not cut on it for a window.
    """

    line: int
    text: str
    t_start_s: float
    t_end_s: float
    max_tracking_error_um: dict[str, float]
    max_cutting_force_N: float
    max_contour_error_um: float | None = None
    rms_contour_error_um: float | None = None
    mean_engagement_deg: float | None = None
    axial_depth_mm: float | None = None
    max_wall_error_um: float | None = None
    stability: LineStability | None = None
    chatter: ChatterCheck | None = None

    def _plain(self) -> tuple[dict[str, Any], dict[str, Any]]:
        """The row's values before and after the tracking errors (those it has)."""
        head: dict[str, Any] = {
            "line": self.line,
            "text": self.text,
            "t_start_s": self.t_start_s,
            "t_end_s": self.t_end_s,
        }
        if self.max_contour_error_um is not None:
            head |= {
                "max_contour_error_um": self.max_contour_error_um,
                "rms_contour_error_um": self.rms_contour_error_um,
            }
        tail: dict[str, Any] = {"max_cutting_force_N": self.max_cutting_force_N}
        if self.mean_engagement_deg is not None:
            tail |= {"mean_engagement_deg": self.mean_engagement_deg, "axial_depth_mm": self.axial_depth_mm}
        if self.max_wall_error_um is not None:
            tail["max_wall_error_um"] = self.max_wall_error_um
        return head, tail

    def to_json(self) -> dict[str, Any]:
        """The row as ``twin run --json`` gives it in ``lines``: what the line has of the
        attributes, in their order, ``stability`` and ``chatter`` as dicts."""
        head, tail = self._plain()
        out = {**head, "max_tracking_error_um": dict(self.max_tracking_error_um), **tail}
        if self.stability is not None:
            out["stability"] = self.stability.to_json()
        if self.chatter is not None:
            out["chatter"] = self.chatter.to_json()
        return out

    def to_columns(self) -> dict[str, Any]:
        """The row flat, as the Parquet per-line table's columns: the tracking errors as
        ``max_tracking_error_um_<axis>``, the chatter check as ``stability_<key>`` with
        ``stable_rpm`` as ``stability_stable_rpm_low`` and ``_high``, the chatter reading as
        ``chatter``, ``chatter_hz``, ``chatter_indicator``, ``chatter_threshold`` and
        ``chatter_windows``."""
        head, tail = self._plain()
        out = {**head, **tail}
        out |= {f"max_tracking_error_um_{axis}": v for axis, v in self.max_tracking_error_um.items()}
        if self.stability is not None:
            out |= self.stability.to_columns()
        if self.chatter is not None:
            out |= self.chatter.to_columns()
        return out

    @property
    def worst_error_um(self) -> float:
        """The line's max contour error (µm), else (a path that is not 2-D) its largest tracking
        error of any axis."""
        if self.max_contour_error_um is not None:
            return self.max_contour_error_um
        return max(self.max_tracking_error_um.values())


@dataclass(frozen=True)
class RunRecords:
    """What a run reports line by line and feature by feature (:func:`twin.metrics.run_records`);
    empty where the run has none of it.

    Attributes
    ----------
    lines : tuple of LineRow
        A program's per-line rows, in program order.
    machining_warnings : tuple of MachiningWarning
        With a stock: the first crashes and misuse; ``machining_warnings_total`` counts them all.
    plan_warnings : tuple of TravelWarning or DriveWarning
        The first warnings against the machine; ``plan_warnings_total`` counts them all.
    inspection : tuple
        With a stock: each ``[[inspect]]`` feature, measured (:class:`CircleMeasured`,
        :class:`LineMeasured`, :class:`WidthMeasured`) or :class:`FeatureNotFound`.
    chatter : ChatterCheck or None
        A milling run's chatter over the whole run; None: it did not mill for a window.
    chatter_warnings : tuple of ChatterWarning
        Each line that chatters, or the run.
    """

    lines: tuple[LineRow, ...] = ()
    machining_warnings: tuple[MachiningWarning, ...] = ()
    machining_warnings_total: int = 0
    plan_warnings: tuple[PlanWarning, ...] = ()
    plan_warnings_total: int = 0
    inspection: tuple[Inspected, ...] = ()
    chatter: ChatterCheck | None = None
    chatter_warnings: tuple[ChatterWarning, ...] = ()

    @property
    def stability_checks(self) -> list[LineStability]:
        """The cutting lines' chatter checks (:attr:`LineRow.stability`), in program order."""
        return [row.stability for row in self.lines if row.stability is not None]
