"""A part program's cut through its stock, made once before the run: the engagement along the
planned path (:func:`~twin.machining.engagement.engagement_table`) as the force model the
compiled loop reads (:class:`ProgramMilling`), the stock as the program leaves it and the
program's crashes and misuse by line (:func:`~twin.machining.misuse.machining_warnings`)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from twin.errors import TwinInputError
from twin.machining.cutting import (
    MIN_SPINDLE_RPM,
    PM_COLUMNS,
    PROGRAM_MILLING,
    PROGRAM_MILLING_SLOTS,
    chip_state,
    helix_lag_rad_per_mm,
    history_rows,
    mode_rows,
    spindle_phase,
)
from twin.machining.engagement import COLUMNS, MAP_MARGIN_MM, HeightMap, StockSpec, ToolSpec, engagement_table
from twin.machining.misuse import machining_warnings
from twin.machining.program_stability import ProgramSamples
from twin.records import MachiningWarning


class ProgramMilling:
    """The milling force of a part program through a stock, for the compiled loop: the
    engagement table (:func:`~twin.machining.engagement.engagement_table`) with the spindle
    speed, its angle and the tool at each sample, read by
    :func:`twin.machining.cutting._program_milling` each physics step.

    Parameters
    ----------
    table : ndarray (n, 6)
        The engagement (:data:`~twin.machining.engagement.COLUMNS`) every ``period_s``.
    spindle_rpm : ndarray (n,)
        Spindle speed at each sample (0: stopped).
    tool_index : ndarray (n,) of int
        Index into ``tools`` at each sample.
    tools : list of ToolSpec
    period_s : float
        The table's sample period (s).
    spindle_phase_rad : float
        Flute 0's angle at t = 0.
    """

    def __init__(self, table, spindle_rpm, tool_index, tools, period_s, spindle_phase_rad=0.0):
        self.table, self.spindle_rpm, self.tool_index = table, spindle_rpm, tool_index
        self.tools, self.period_s, self.spindle_phase_rad = list(tools), period_s, spindle_phase_rad

    def kernel_arrays(self, machine) -> tuple[int, np.ndarray, np.ndarray]:
        """``(PROGRAM_MILLING, params, state)`` for :func:`twin.machining.cutting.workpiece_forces`."""

        dt = machine.model.opt.timestep
        omega = 2.0 * math.pi * self.spindle_rpm / 60.0
        angle = self.spindle_phase_rad + np.concatenate([[0.0], np.cumsum(omega[:-1] * self.period_s)])
        flutes = np.array([t.n_flutes for t in self.tools])[self.tool_index]
        turning = self.spindle_rpm >= MIN_SPINDLE_RPM
        lag = np.max(2.0 * math.pi / (omega[turning] * flutes[turning]) / dt) if turning.any() else 1.0
        n_hist = history_rows(lag)
        columns = {name: self.table[:, COLUMNS.index(name)] for name in COLUMNS}
        columns.update(omega=omega, angle=angle, tool=self.tool_index)
        rows = np.column_stack([columns[name] for name in PM_COLUMNS]).astype(float)
        tools = [
            np.concatenate(
                [t.cutting_coefficients().as_array(), [t.n_flutes, helix_lag_rad_per_mm(t.helix_deg, t.diameter_mm)]]
            )
            for t in self.tools
        ]
        jacobian = np.asarray(machine.workpiece_jacobian(), float).ravel()
        modes = mode_rows([t.dynamics for t in self.tools], dt)
        values = (len(self.tools), self.period_s, len(rows), dt, n_hist, jacobian.size, len(modes))
        head = dict(zip(PROGRAM_MILLING_SLOTS, values))
        params = np.concatenate(
            [[float(head[name]) for name in PROGRAM_MILLING_SLOTS], jacobian, *tools, modes.ravel(), rows.ravel()]
        )
        most_flutes = max((t.n_flutes for t in self.tools), default=1)
        state = chip_state(n_hist, (0.0, 0.0), len(modes), most_flutes)  # no force before the first move
        return PROGRAM_MILLING, params, state


@dataclass
class ProgramCut:
    """A planned program through its stock (:func:`program_milling`).

    Attributes
    ----------
    milling : ProgramMilling
        The force model for the run.
    table : ndarray (n, len(COLUMNS))
        The engagement at each sample of the plan.
    height_map : HeightMap
        The stock as the program leaves it.
    warnings : list of twin.records.MachiningWarning
        Crashes and misuse by line (:func:`twin.machining.misuse.machining_warnings`).
    warnings_total : int
        Every warning, listed or not.
    radius_m, corner_m : ndarray (n,)
        The tool's radius and corner radius at each sample (m).
    """

    milling: ProgramMilling
    table: np.ndarray
    height_map: HeightMap
    warnings: list[MachiningWarning]
    warnings_total: int
    radius_m: np.ndarray
    corner_m: np.ndarray

    def samples(self, plan) -> ProgramSamples:
        """The engagement, spindle speed, tool, line and XY velocity at each sample of ``plan``
        (the :class:`twin.gcode.planner.Plan` this cut was made from), for the chatter check
        (:func:`twin.machining.program_stability.line_stability`)."""
        milling = self.milling
        return ProgramSamples(
            self.table, milling.spindle_rpm, milling.tool_index, milling.tools, plan.line, plan.velocity[:, :2]
        )


def program_milling(plan, stock: StockSpec, tool: ToolSpec | None, tools: list[ToolSpec], seed: int) -> ProgramCut:
    """The stock cut by a planned program: the force model, its engagement table and warnings.

    Parameters
    ----------
    plan : twin.gcode.planner.Plan
    stock : StockSpec
    tool : ToolSpec or None
        The tool of a program without T words.
    tools : list of ToolSpec
        The tools of a program that changes them, by ``number``.
    seed : int
        Seeds the spindle's angle at t = 0.

    Raises
    ------
    TwinInputError
        No tool given, a tool without a number in ``[[tools]]`` or a number twice, or a T word
        with no such tool (naming the program line).
    """
    if tool is None and not tools:
        raise TwinInputError("tool", None, "a stock is cut by a tool: give [tool] or [[tools]]")
    by_number: dict[int, ToolSpec] = {}
    for i, t in enumerate(tools):
        if t.number is None:
            raise TwinInputError(f"tools.{i}.number", None, "each of [[tools]] needs its T number")
        if t.number in by_number:
            raise TwinInputError(f"tools.{i}.number", t.number, "two tools with one number")
        by_number[t.number] = t
    numbers = plan.per_sample(plan.tools, 0)
    chosen: list[ToolSpec] = []
    index = np.zeros(len(numbers), int)
    for number in np.unique(numbers):
        if int(number) in by_number:
            spec = by_number[int(number)]
        elif tool is not None and (number == 0 or not by_number):
            spec = tool
        else:
            line = next(line for line, t in plan.tools.items() if t == number)
            raise TwinInputError(
                f"program line {line}", f"T{int(number)}", f"no such tool (tools: {sorted(by_number)})"
            )
        chosen.append(spec)
        index[numbers == number] = len(chosen) - 1
    radius = np.array([t.diameter_mm for t in chosen])[index] * 0.5e-3
    corner = np.array([t.corner_radius_mm for t in chosen])[index] * 1e-3
    flute = np.array([math.inf if t.flute_length_mm is None else t.flute_length_mm for t in chosen])[index] * 1e-3
    shank = np.array([t.shank_diameter_mm or 0.0 for t in chosen])[index] * 0.5e-3
    rpm = plan.per_sample(plan.spindle_rpm, 0.0)
    height_map = HeightMap(stock, MAP_MARGIN_MM)
    table = engagement_table(
        plan.position,
        plan.velocity,
        radius_m=radius,
        height_map=height_map,
        corner_m=corner,
        flute_m=flute,
        shank_m=shank,
    )
    model = ProgramMilling(table, rpm, index, chosen, plan.period_s, spindle_phase(None, seed))
    warnings, total = machining_warnings(plan, table, chosen, index, rpm, stock)
    return ProgramCut(model, table, height_map, warnings, total, radius, corner)
