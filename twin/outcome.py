"""A run's outcome, the one way a run goes: the program planned and cut before the run
(:class:`PlannedProgram`), the run producing the motion (:func:`twin.sim.runner.simulate`), and
after it the part that motion cut, its inspection and the program's warnings
(:func:`finish`), held in one frozen object (:class:`RunOutcome`) that the metrics, the report,
the plots and the recording read.

The reference a run follows says only what the program does at each time (its samples, line,
feed, engagement); what is said of the whole program is here.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from twin.errors import RunInterrupted, SimulationDiverged
from twin.gcode.checks import DriveCheck, TravelCheck, plan_warnings
from twin.gcode.planner import Plan
from twin.machining.engagement import StockSpec
from twin.machining.inspection import InspectSpec, inspect
from twin.machining.part import MachinedPart, part_cut_by_motion
from twin.machining.program_cut import ProgramCut
from twin.machining.program_stability import default_rpm_range, line_stability
from twin.machining.sweep import ToolSweep
from twin.records import Inspected, LineStability, MachiningWarning, PlanWarning
from twin.sim.runner import RunResult


@dataclass(frozen=True)
class PlannedProgram:
    """A part program as made before its run.

    Attributes
    ----------
    checks : tuple of TravelCheck, DriveCheck or None
        The checks of the program against the machine (:mod:`twin.gcode.checks`); a program
        too long to hold has its drive check fed as the run samples it, so its warnings are
        read after the run.
    plan : twin.gcode.planner.Plan or None
        The planned program held whole; None for one planned as the run asks for it.
    cut : ProgramCut or None
        With a stock: the program through it (:func:`twin.machining.program_cut.program_milling`).
    stock : StockSpec or None
        The stock it cuts.
    features : tuple of InspectSpec
        The ``[[inspect]]`` features measured on the part after the run.
    line_stability : dict of int to twin.records.LineStability
        With a stock and tools with ``dynamics``: each cutting line's chatter check
        (:func:`twin.machining.program_stability.line_stability`, stable speeds searched over
        :func:`~twin.machining.program_stability.default_rpm_range`); else empty.
    """

    checks: tuple[TravelCheck | DriveCheck | None, ...]
    plan: Plan | None = None
    cut: ProgramCut | None = None
    stock: StockSpec | None = None
    features: tuple[InspectSpec, ...] = ()
    line_stability: dict[int, LineStability] = field(default_factory=dict)


def planned_program(
    checks: tuple[TravelCheck | DriveCheck | None, ...],
    plan: Plan | None,
    cut: ProgramCut | None = None,
    stock: StockSpec | None = None,
    features: tuple[InspectSpec, ...] = (),
) -> PlannedProgram:
    """The program before its run (see :class:`PlannedProgram`), each cutting line's chatter
    check done, so that its bad input is caught before the run."""
    stability: dict[int, LineStability] = {}
    if cut is not None and plan is not None:
        samples = cut.samples(plan)
        stability = line_stability(samples, default_rpm_range(samples.spindle_rpm))
    return PlannedProgram(checks, plan, cut, stock, features, stability)


@dataclass(frozen=True)
class RunOutcome:
    """A run and what is computed from its motion: with a part program its warnings and line
    checks, with a stock the part cut and its inspection.

    Attributes
    ----------
    run : twin.sim.runner.RunResult
        The run's arrays at the recorded ticks, and metrics over every tick.
    cut : ProgramCut or None
        With a stock: the program's planned cut through it.
    part : twin.machining.part.MachinedPart or None
        With a stock, for a run that went to its end: the part the actual motion cut, against
        the nominal one.
    inspection : tuple of twin.records.Inspected
        The ``[[inspect]]`` features measured on it (:func:`twin.machining.inspection.inspect`).
    plan_warnings : tuple of TravelWarning or DriveWarning
        A program's moves outside the travel (under ``travel = "warn"``) and what the drives
        cannot deliver, by line, the first ones; ``plan_warnings_total`` counts them all.
    line_stability : dict of int to twin.records.LineStability
        With a stock and a tool with ``dynamics``: each cutting line's chatter check.
    stopped : SimulationDiverged or RunInterrupted or None
        What stopped a run early; None for a run that went to its end.
    """

    run: RunResult
    cut: ProgramCut | None = None
    part: MachinedPart | None = None
    inspection: tuple[Inspected, ...] = ()
    plan_warnings: tuple[PlanWarning, ...] = ()
    plan_warnings_total: int = 0
    line_stability: dict[int, LineStability] = field(default_factory=dict)
    stopped: SimulationDiverged | RunInterrupted | None = None

    @property
    def machining_warnings(self) -> tuple[MachiningWarning, ...]:
        """With a stock: the program's first crashes and misuse by line
        (:func:`twin.machining.misuse.machining_warnings`)."""
        return () if self.cut is None else tuple(self.cut.warnings)

    @property
    def machining_warnings_total(self) -> int:
        """How many crashes and misuse there are in all."""
        return 0 if self.cut is None else self.cut.warnings_total

    @cached_property
    def outlines(self) -> dict[str, list[np.ndarray]]:
        """With a stock: its outline and the machined one (mm, see
        :meth:`twin.machining.engagement.HeightMap.outlines`, computed once); else empty."""
        return {} if self.cut is None else self.cut.height_map.outlines()


def finish(
    run: RunResult, program: PlannedProgram | None, stopped: SimulationDiverged | RunInterrupted | None = None
) -> RunOutcome:
    """What follows a run (``stopped`` early, or not): with a part ``program``, its warnings
    against the machine, and with a stock, for a run that went to its end and recorded its
    ticks, the part its actual motion cut (the table's measured path at the recorded ticks, the
    planned Z and tool of the planned sample at each, :func:`twin.machining.part.part_cut_by_motion`)
    and the features measured on it."""
    if program is None:
        return RunOutcome(run, stopped=stopped)
    listed, total = plan_warnings(*program.checks)
    part: MachinedPart | None = None
    inspection: tuple[Inspected, ...] = ()
    if (
        stopped is None
        and program.cut is not None
        and program.stock is not None
        and program.plan is not None
        and run.program is not None
        and len(run.t_s)
    ):
        part = part_cut_by_motion(
            program.stock,
            ToolSweep.planned(program.plan, program.cut),
            period_s=program.plan.period_s,
            t_s=run.t_s,
            table_xy_mm=run.table_position_m()[:, :2] * 1e3,
            lines=run.program.lines,
        )
        inspection = inspect(program.features, part, program.stock)
    return RunOutcome(
        run,
        cut=program.cut,
        part=part,
        inspection=inspection,
        plan_warnings=tuple(listed),
        plan_warnings_total=total,
        line_stability=program.line_stability,
        stopped=stopped,
    )
