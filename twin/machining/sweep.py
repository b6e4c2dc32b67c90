"""A tool path through the stock as the part is cut along it (:mod:`twin.machining.part`,
:mod:`twin.machining.part_map`): the planned one, or where the twin moved the tool."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass
class ToolSweep:
    """A tool path through the stock, all in mm.

    Attributes
    ----------
    xy_mm : ndarray (n, 2)
        The tool's axis relative to the stock.
    tip_mm, radius_mm, corner_mm : ndarray (n,)
        Its tip height, radius and corner radius.
    line : ndarray (n,) of int
        The program line at each sample.
    """

    xy_mm: np.ndarray
    tip_mm: np.ndarray
    radius_mm: np.ndarray
    corner_mm: np.ndarray
    line: np.ndarray

    @classmethod
    def planned(cls, plan, cut) -> ToolSweep:
        """The planned path of a program through its stock: a
        :class:`twin.gcode.planner.Plan`'s tips with the tool of each sample of its
        :class:`twin.machining.program_cut.ProgramCut`."""
        xyz = plan.position * 1e3
        return cls(xyz[:, :2], xyz[:, 2], cut.radius_m * 1e3, cut.corner_m * 1e3, plan.line)
