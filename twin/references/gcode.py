"""A part program as the reference: the G-code reader (:mod:`twin.gcode.reader`) and the
look-ahead, jerk-limited interpolator (:mod:`twin.gcode.planner`), planned at build time within
the machine's motion limits and the scenario's ``[planner]`` table.

The XY table follows the program's X and Y; Z is planned too and recorded (``reference/z``),
the machine having no Z axis.
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from typing import ClassVar, Literal

import numpy as np
from pydantic import Field, PositiveFloat

from twin.errors import TwinInputError, input_file
from twin.gcode.checks import DriveCheck, TravelCheck, plan_warnings
from twin.gcode.planned import SAMPLE_PERIOD_S, PlanningError
from twin.gcode.planner import (
    MAX_PROGRAM_SAMPLES,
    MAX_SAMPLES,
    PROGRAM_LIMIT,
    Plan,
    PlannerSettings,
    hold_or_count,
    plan,
    plan_stream,
    refuse_long,
)
from twin.gcode.reader import Reader, Settings
from twin.gcode.report import PlannedSummary, planned_summary
from twin.machines import BuiltMachine
from twin.machines import build as build_machine
from twin.machines.rigid_drive import rigid_drives, table_travel_m
from twin.machining.engagement import COLUMNS, engaged_degrees
from twin.machining.program_cut import ProgramCut
from twin.references.kinds import ReferenceContext, ReferenceSpecBase, register, two_axes
from twin.settings import set_fields
from twin.spec import Millimetres, StrictSpec, validation_error

#: The work coordinate systems a program may select.
WORK_SYSTEMS = ("G54", "G55", "G56", "G57", "G58", "G59")


#: What a run with a stock refuses a longer program for.
STOCK_LIMIT = (
    f"the {MAX_SAMPLES * SAMPLE_PERIOD_S:.0f} s a program cut in a stock may run (it is planned whole: split it, "
    "or run it without the stock)"
)

#: Samples (1 ms each) a run's reference holds whole at most; a longer program without a stock
#: is planned again as the run asks for it (a second pass: memory stays bounded).
HELD_SAMPLES = 600_000


def _hermite(p: np.ndarray, v: np.ndarray, k: np.ndarray, f: np.ndarray, dt: float) -> np.ndarray:
    """Cubic Hermite interpolation of positions ``p`` with slopes ``v`` between samples ``k`` and
    ``k + 1`` at fractions ``f`` (column)."""
    h00, h10 = 2 * f**3 - 3 * f**2 + 1, f**3 - 2 * f**2 + f
    h01, h11 = -2 * f**3 + 3 * f**2, f**3 - f**2
    return h00 * p[k] + h10 * dt * v[k] + h01 * p[k + 1] + h11 * dt * v[k + 1]


class _Samples:
    """The common reading of a planned reference over a stretch of its samples: position by
    cubic Hermite interpolation between them (velocity as slopes), velocity and acceleration
    linearly; at rest before the start and after the end."""

    axes: tuple[int, ...]
    n_axes: int
    period_s: float
    n_samples: int

    def _window(self, t: np.ndarray):
        """The samples covering times ``t``: (first index, position, velocity, acceleration, line)."""
        raise NotImplementedError

    def _at(self, t: np.ndarray):
        dt = self.period_s
        x = np.clip(np.asarray(t, float) / dt, 0.0, self.n_samples - 1)
        k = np.minimum(x.astype(int), max(self.n_samples - 2, 0))
        return k, x - k, dt

    def positions(self, t) -> np.ndarray:
        """Positions of x, y, z (m) at times ``t``, shape (len(t), 3)."""
        t = np.atleast_1d(np.asarray(t, float))
        first, p, v, _a, _l = self._window(t)
        if self.n_samples < 2:
            return np.broadcast_to(p[0], (t.size, 3)).copy()
        k, f, dt = self._at(t)
        return _hermite(p, v, k - first, f[:, None], dt)

    def sample(self, t) -> np.ndarray:
        """Position, velocity and acceleration of the machine's axes, shape (len(t), n_axes, 3)."""
        t = np.atleast_1d(np.asarray(t, float))
        out = np.zeros((t.size, self.n_axes, 3))
        first, p, v, a, _l = self._window(t)
        if self.n_samples < 2:
            out[:, :, 0] = p[0, list(self.axes)]
            return out
        k, f, dt = self._at(t)
        k = k - first
        f = f[:, None]
        pos = _hermite(p, v, k, f, dt)
        vel = (1 - f) * v[k] + f * v[k + 1]
        acc = (1 - f) * a[k] + f * a[k + 1]
        for i, axis in enumerate(self.axes):
            out[:, i] = np.stack([pos[:, axis], vel[:, axis], acc[:, axis]], axis=1)
        return out

    def extra_series(self, t) -> dict[str, np.ndarray]:
        """The planned axes the machine does not have, by name (m): what the recording adds."""
        pos = self.positions(t)
        return {name: pos[:, i] for i, name in enumerate("xyz") if i not in self.axes}

    def line_at(self, t: float) -> int:
        """The program line the reference is on at time ``t`` (s)."""
        return int(self.lines_at(np.array([t]))[0])

    def lines_at(self, t) -> np.ndarray:
        """The program line at each time of ``t`` (s)."""
        t = np.atleast_1d(np.asarray(t, float))
        first, _p, _v, _a, line = self._window(t)
        k = np.clip(np.rint(t / self.period_s).astype(int), 0, self.n_samples - 1)
        return line[k - first]


class GcodeReference(_Samples):
    """A planned program held whole, sampled at any time.

    Parameters
    ----------
    planned : Plan
        The interpolator's output (machine axes x, y, z).
    axes : tuple of int
        Which of x, y, z (indices) the machine's axes follow, in its order.
    n_lines : int
        The program's lines read, to its end (M2, M30, the second %) (for the progress bar).
    cut : twin.machining.program_cut.ProgramCut or None
        With a stock: the program through it (the engagement at each sample).
    checks : tuple of TravelCheck, DriveCheck or None
        The checks of the program against the machine (:mod:`twin.gcode.checks`), done; their
        warnings are read with the program's (:class:`twin.outcome.PlannedProgram`), not here.
    """

    def __init__(
        self,
        planned: Plan,
        axes: tuple[int, ...],
        n_lines: int,
        cut: ProgramCut | None = None,
        checks: tuple[TravelCheck | DriveCheck | None, ...] = (),
    ):
        self.plan, self.axes, self.n_lines, self.cut, self.checks = planned, axes, n_lines, cut, checks
        self.n_axes = len(axes)
        self.period_s = planned.period_s
        self.n_samples = len(planned.position)

    def cutting(self, cut: ProgramCut) -> GcodeReference:
        """The same program cutting a stock (``cut``, :func:`twin.machining.program_cut.program_milling`)."""
        return GcodeReference(self.plan, self.axes, self.n_lines, cut, self.checks)

    def _window(self, t):
        return 0, self.plan.position, self.plan.velocity, self.plan.acceleration, self.plan.line

    @property
    def duration_s(self) -> float:
        """The program's cycle time (s)."""
        return self.plan.cycle_time_s

    def engagement_at(self, t) -> np.ndarray:
        """The engaged angle (deg) and axial depth (mm) at times ``t`` (s), shape (len(t), 2);
        empty without a stock."""
        if self.cut is None:
            return np.zeros((0, 2))
        table = self.cut.table
        k = np.clip(np.rint(np.asarray(t, float) / self.plan.period_s).astype(int), 0, len(table) - 1)
        rows = table[k]
        return np.column_stack([engaged_degrees(rows), rows[:, COLUMNS.index("max_depth_mm")]])

    def feeds_at(self, t) -> np.ndarray:
        """The programmed feed (mm/min; 0 on rapids and dwells) at times ``t`` (s)."""
        return _by_line(self.lines_at(t), self.plan.feeds)

    @property
    def texts(self) -> dict[int, str]:
        """The text of each program line that moved or dwelt."""
        return self.plan.texts


class StreamedGcodeReference(_Samples):
    """A planned program too long to hold, planned again as the run asks for its samples
    (times only ever increase): a window of samples is kept, so memory stays bounded.

    Parameters
    ----------
    moves : callable
        A fresh stream of the program's moves (it is read again).
    limits, settings
        What it was planned with.
    facts : ProgramFacts
        What the first pass learnt (line texts, feeds).
    n_samples : int
        The reference's length (the first pass's count).
    axes : tuple of int
        Which of x, y, z the machine's axes follow.
    n_lines : int
        The program's lines read, to its end.
    checks : tuple of TravelCheck, DriveCheck or None
        The checks of the program against the machine: the drive's is fed the samples as they
        are planned (its warnings are complete once the run has reached the program's end).
    """

    def __init__(
        self,
        moves,
        limits,
        settings,
        facts,
        n_samples: int,
        axes: tuple[int, ...],
        n_lines: int,
        checks: tuple[TravelCheck | DriveCheck | None, ...] = (),
    ):
        self.axes, self.n_axes, self.n_lines, self.checks = axes, len(axes), n_lines, checks
        self.period_s = SAMPLE_PERIOD_S
        self.n_samples = n_samples
        self.facts = facts
        self.chunks, _facts = plan_stream(moves(), limits, settings)
        self.first = 0
        self.held = (np.zeros((0, 3)), np.zeros((0, 3)), np.zeros((0, 3)), np.zeros(0, int))

    def _window(self, t):
        dt = self.period_s
        lo = max(int(np.floor(float(np.min(t)) / dt)) - 2, 0)
        hi = min(int(np.ceil(float(np.max(t)) / dt)) + 2, self.n_samples)
        if lo < self.first:
            raise ValueError(f"the streamed reference has moved past t = {float(np.min(t)):.6f} s")
        p, v, a, line = self.held
        drop = lo - self.first
        parts = [(p[drop:], v[drop:], a[drop:], line[drop:])]
        end = self.first + len(p)
        while end < hi:
            chunk = next(self.chunks)
            for check in self.checks:
                if isinstance(check, DriveCheck):
                    check.add(chunk.position, chunk.velocity, chunk.acceleration, chunk.line, self.facts.texts)
            parts.append((chunk.position, chunk.velocity, chunk.acceleration, chunk.line))
            end += len(chunk.position)
        if len(parts) > 1 or drop:
            self.held = tuple(np.concatenate(column) for column in zip(*parts))
            self.first = lo
        p, v, a, line = self.held
        return self.first, p, v, a, line

    @property
    def duration_s(self) -> float:
        """The program's cycle time (s)."""
        return (self.n_samples - 1) * self.period_s

    def engagement_at(self, t) -> np.ndarray:
        """No stock: empty."""
        return np.zeros((0, 2))

    def feeds_at(self, t) -> np.ndarray:
        """The programmed feed (mm/min; 0 on rapids and dwells) at times ``t`` (s)."""
        return _by_line(self.lines_at(t), self.facts.feeds)

    @property
    def texts(self) -> dict[int, str]:
        return self.facts.texts


def _by_line(lines: np.ndarray, by_line: dict) -> np.ndarray:
    """A per-line value at each of ``lines``."""
    known, where = np.unique(lines, return_inverse=True)
    return np.array([by_line.get(int(line), 0.0) for line in known])[where]


class GcodeRef(ReferenceSpecBase):
    """gcode: a part program (LinuxCNC's dialect) through the look-ahead, jerk-limited interpolator."""

    type: Literal["gcode"]
    file: str = Field(description="the program; a relative path is relative to the scenario file")
    work_offsets_mm: dict[
        Literal["G54", "G55", "G56", "G57", "G58", "G59"], tuple[Millimetres, Millimetres, Millimetres]
    ] = Field(default_factory=dict, description="work offsets [x, y, z] in machine coordinates, mm (default 0)")
    tool_lengths_mm: dict[int, Millimetres] = Field(
        default_factory=dict, description="tool length (G43) by tool number, mm"
    )
    tool_diameters_mm: dict[int, Millimetres] = Field(
        default_factory=dict,
        description="tool diameter by tool number, mm: cutter radius compensation (G41/G42 D); negative: other side",
    )
    g28_home_mm: tuple[Millimetres, Millimetres, Millimetres] = Field(
        (0.0, 0.0, 0.0), description="G28's home, machine mm"
    )

    #: Fields that hold a path relative to the scenario file.
    relative_paths: ClassVar[tuple[str, ...]] = ("file",)

    def reader_settings(
        self, tools: frozenset[int] | None = None, diameters_mm: dict[int, float] | None = None
    ) -> Settings:
        """The settings the reader takes from this table, the tool numbers a T word may select
        (None: any) and the diameters of the scenario's ``[[tools]]`` (this table's
        ``tool_diameters_mm`` over them)."""
        return Settings(
            work_offsets_mm={WORK_SYSTEMS.index(k) + 1: v for k, v in self.work_offsets_mm.items()},
            tool_lengths_mm=dict(self.tool_lengths_mm),
            g28_home_mm=self.g28_home_mm,
            tools=tools,
            tool_diameters_mm={**(diameters_mm or {}), **self.tool_diameters_mm},
        )


def build(spec: GcodeRef, ctx: ReferenceContext) -> GcodeReference | StreamedGcodeReference:
    """Read and plan the program for the machine of ``ctx``.

    Raises
    ------
    TwinInputError
        ``reference.file`` naming the program's line and the reason; or the planner's settings.
    """
    two_axes(spec.type, ctx.axis_names)
    if ctx.machine is None:
        raise TwinInputError("reference.type", spec.type, "a program is planned for a machine: give one")
    unknown = [a for a in ctx.axis_names if a not in "xyz"]
    if unknown:
        raise TwinInputError("reference.type", spec.type, f"the machine's axes {ctx.axis_names} are not x, y, z")
    settings = ctx.planner if isinstance(ctx.planner, PlannerSettings) else PlannerSettings.model_validate(ctx.planner)
    settings = with_machine_mode(settings, ctx.machine)
    path = input_file(spec.file, "reference.file")
    reader_settings = spec.reader_settings(ctx.tools, ctx.tool_diameters_mm)
    limits = settings.limits(ctx.machine.motion_limits)
    axes = tuple("xyz".index(a) for a in ctx.axis_names)
    reader = Reader(None, reader_settings, str(path), path=path)
    most, limit = (MAX_SAMPLES, STOCK_LIMIT) if ctx.stock else (MAX_PROGRAM_SAMPLES, PROGRAM_LIMIT)
    travel, drive = program_checks(ctx.machine, settings, ctx.saturation_V)
    with planning_errors("reference.file", spec.file):
        # a lower bound of its time from the moves alone first (and the travel): a program too
        # long, or outside the travel, is refused before any of it is planned
        refuse_long(
            travel.passing(Reader(None, reader_settings, str(path), path=path).moves()),
            limits,
            settings,
            most_s=most * SAMPLE_PERIOD_S,
            limit=limit,
        )
        held, facts, samples = hold_or_count(
            reader.moves(), limits, settings, most=MAX_SAMPLES if ctx.stock else HELD_SAMPLES
        )
    if held is not None:
        if drive is not None:
            drive.add(held.position, held.velocity, held.acceleration, held.line, held.texts)
        return GcodeReference(held, axes, reader.lines_read, checks=(travel, drive))
    if samples > MAX_PROGRAM_SAMPLES:
        raise TwinInputError(
            "reference.file",
            spec.file,
            f"the program runs longer than {MAX_PROGRAM_SAMPLES * SAMPLE_PERIOD_S / 3600:.0f} hours of motion",
        )
    if ctx.stock:
        raise TwinInputError(
            "reference.file",
            spec.file,
            f"the program runs {samples * SAMPLE_PERIOD_S:.0f} s: a program cut in a stock is planned whole, at most "
            f"{MAX_SAMPLES * SAMPLE_PERIOD_S:.0f} s; split it, or run it without the stock",
        )
    return StreamedGcodeReference(
        lambda: Reader(None, reader_settings, str(path), path=path).moves(),
        limits,
        settings,
        facts,
        samples,
        axes,
        reader.lines_read,
        (travel, drive),
    )


register("gcode", GcodeRef, build)


@contextmanager
def planning_errors(field: str, file) -> Iterator[None]:
    """A program's planning error (:class:`~twin.gcode.planned.PlanningError`) as the twin's input
    error under ``field``, naming the program ``file``: the one translation of every door that
    plans a program (a run's reference, ``twin gcode --machine``, ``twin.program``)."""
    try:
        yield
    except PlanningError as exc:
        raise TwinInputError(field, str(file), str(exc)) from None


def with_machine_mode(settings: PlannerSettings, machine) -> PlannerSettings:
    """The planner's settings with the machine file's ``planner_mode`` where the scenario (or
    ``--set planner.mode``) gives none."""
    if "mode" in settings.model_fields_set or machine.planner_mode is None:
        return settings
    return settings.model_copy(update={"mode": machine.planner_mode})


def program_checks(
    machine: BuiltMachine, settings: PlannerSettings, saturation_V: float | None
) -> tuple[TravelCheck, DriveCheck | None]:
    """The checks of a program against ``machine`` (:mod:`twin.gcode.checks`): its axes' travel
    (none where its model's slides have no range: the papers' machines), and its drives where
    the drive saturates (``saturation_V``, V; None: no drive check)."""
    travel = TravelCheck({"xyz".index(a): r for a, r in table_travel_m(machine).items()}, settings.travel == "refuse")
    if saturation_V is None:
        return travel, None
    return travel, DriveCheck({"xyz".index(a): d for a, d in rigid_drives(machine).items()}, saturation_V)


def planned_for(
    file, moves: list, machine: str, planner: PlannerSettings, saturation_V: float | None = None
) -> PlannedSummary:
    """The ``planned`` table of ``twin gcode --machine``: the ``moves`` of ``file`` planned for
    ``machine`` (:func:`twin.gcode.report.planned_summary`), checked against its travel and, with
    ``saturation_V`` (V), its drives (its ``warnings``).

    Raises
    ------
    TwinInputError
        An unknown machine, or a program the planner refuses (named as ``file``), a move outside
        the travel under ``travel = "refuse"`` among them.
    """
    built = build_machine(machine)
    planner = with_machine_mode(planner, built)
    limits = planner.limits(built.motion_limits)
    travel, drive = program_checks(built, planner, saturation_V)
    with planning_errors("file", file):
        travel.check(moves)
        planned = plan(moves, limits, planner)
    if drive is not None:
        drive.add(planned.position, planned.velocity, planned.acceleration, planned.line, planned.texts)
    warnings, total = plan_warnings(travel, drive)
    return planned_summary(planned, limits, warnings=warnings, warnings_total=total)


class ProgramDrive(StrictSpec):
    """``twin gcode --set drive.saturation_V=V``: the drive a program is checked against (a
    scenario's ``[drive]`` table gives it to a run)."""

    saturation_V: PositiveFloat | None = Field(None, description="the drive's saturation, V (None: no drive check)")


def program_settings(file: str, settings: dict):
    """The reader's table, the planner's settings and the drive's saturation (V or None) for
    ``twin gcode FILE``: ``settings`` are dotted paths below ``reference.`` (work_offsets_mm,
    tool_lengths_mm, tool_diameters_mm, g28_home_mm), ``planner.``
    (:class:`~twin.gcode.planner.PlannerSettings`) and ``drive.`` (:class:`ProgramDrive`).

    Raises
    ------
    TwinInputError
        A path outside those tables, or a value they cannot take (named).
    """
    from pydantic import ValidationError

    tables: dict[str, type[StrictSpec]] = {"reference": GcodeRef, "planner": PlannerSettings, "drive": ProgramDrive}
    for path in settings:
        if str(path).split(".")[0] not in tables or "." not in str(path):
            raise TwinInputError(f"--set {path}", settings[path], "give planner.KEY, reference.KEY or drive.KEY")
    data = set_fields({"reference": {"type": "gcode", "file": file}, "planner": {}, "drive": {}}, settings, "--set ")
    parsed = {}
    for key, model in tables.items():
        try:
            parsed[key] = model.model_validate(data[key])
        except ValidationError as exc:
            raise validation_error(exc, data[key], f"{key}.") from None
    drive = parsed["drive"]
    assert isinstance(drive, ProgramDrive)
    return parsed["reference"], parsed["planner"], drive.saturation_V
