"""Every cutting line of a program checked against chatter (twin.machining.program_stability)."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from twin.machining.engagement import COLUMNS, ToolSpec
from twin.machining.program_stability import ProgramSamples, describe, line_stability
from twin.machining.stability import Cut, zoa_critical_depths
from twin.records import LineStability

MODES = [{"direction": d, "frequency_hz": 3150.0, "damping_ratio": 0.03, "stiffness_N_per_m": 6e6} for d in ("x", "y")]
TOOL = ToolSpec.model_validate({"diameter_mm": 10.0, "n_flutes": 2, "dynamics": {"modes": MODES}})


def samples(lines_arcs_depths_rpm):
    """A program of one sample per (line, (phi_st, phi_ex), depth mm, rpm), feeding along X at 1 m/min."""
    rows = []
    for _line, (st, ex), depth, _rpm in lines_arcs_depths_rpm:
        row = np.zeros(len(COLUMNS))
        row[[COLUMNS.index(c) for c in ("phi_st1", "phi_ex1", "depth1_mm", "max_depth_mm", "radius_mm")]] = (
            st,
            ex,
            depth,
            depth,
            5.0,
        )
        rows.append(row)
    n = len(rows)
    return ProgramSamples(
        table=np.array(rows),
        spindle_rpm=np.array([r for *_, r in lines_arcs_depths_rpm], float),
        tool_index=np.zeros(n, int),
        tools=[TOOL],
        line=np.array([line for line, *_ in lines_arcs_depths_rpm]),
        velocity_xy=np.tile([1.0 / 60, 0.0], (n, 1)),
    )


def test_a_slot_line_gets_the_lobes_critical_depth_and_its_stable_speeds():
    """The line's critical depth is the zero-order one of its cut at its speed; its stable
    range's ends are stable and the speeds just outside them not (the 2000-speed grid's step)."""
    program = samples([(7, (0.0, math.pi), 1.0, 12000.0), (8, (0.0, math.pi), 0.1, 12000.0)])
    checked = line_stability(program, (3000.0, 24000.0))
    k = TOOL.cutting_coefficients()
    cut = Cut(2, k.K_tc * 1e6, k.K_rc / k.K_tc, ((0.0, math.pi, 1.0),))
    dyn = TOOL.dynamics
    expected = zoa_critical_depths(cut, dyn, [12000.0]).critical_depth_m[0] * 1e3
    row = checked[7]
    assert row.critical_depth_mm == pytest.approx(expected, rel=1e-3)
    assert row.margin == pytest.approx(expected / 1.0, rel=1e-3)
    assert row.margin < 1 and checked[8].margin > 1
    low, high = row.stable_rpm
    step = (24000.0 - 3000.0) / 1999
    inside = zoa_critical_depths(cut, dyn, [low + step, high - step]).critical_depth_m * 1e3
    outside = zoa_critical_depths(cut, dyn, [low - 2 * step, high + 2 * step]).critical_depth_m * 1e3
    assert np.all(inside > 1.0) and np.all(outside < 1.0)
    assert checked[8].stable_rpm[0] <= 12000.0 <= checked[8].stable_rpm[1]  # its own speed is stable


def test_a_line_reports_its_worst_sample_and_a_tool_without_dynamics_none():
    program = samples([(3, (0.0, math.pi / 2), 1.0, 9000.0), (3, (0.0, math.pi), 1.0, 9000.0)])
    both = line_stability(program, (3000.0, 24000.0))
    slot_only = line_stability(samples([(3, (0.0, math.pi), 1.0, 9000.0)]), (3000.0, 24000.0))
    assert both[3].critical_depth_mm == slot_only[3].critical_depth_mm
    plain = ToolSpec.model_validate({"diameter_mm": 10.0, "n_flutes": 2})
    assert line_stability(ProgramSamples(**{**program.__dict__, "tools": [plain]}), (3000.0, 24000.0)) == {}


def test_the_line_a_user_reads():
    row = {"depth_mm": 4.0, "spindle_rpm": 12000.0, "critical_depth_mm": 2.1, "stable_rpm": (13400.0, 15100.0)}
    assert describe(57, **row) == "line 57: 4.00 mm at 12 000 rpm, critical 2.10 mm; stable at 13 400-15 100 rpm"


def test_a_checked_line_is_over_its_critical_depth_only_with_a_boundary_under_its_depth():
    """A margin under 1 is over; no boundary (margin None) is not; the JSON and the per-line
    table's columns keep the untyped dict's keys and order."""
    check = LineStability(
        depth_mm=4.0,
        spindle_rpm=12000.0,
        critical_depth_mm=2.1,
        margin=0.525,
        chatter_hz=3100.5,
        stable_rpm=(13400.0, 15100.0),
        text="line 57: ...",
    )
    unbounded = replace(check, critical_depth_mm=None, margin=None, chatter_hz=None, stable_rpm=None)
    assert check.over_critical and not unbounded.over_critical
    assert list(check.to_json()) == [
        "depth_mm",
        "spindle_rpm",
        "critical_depth_mm",
        "margin",
        "chatter_hz",
        "stable_rpm",
        "text",
    ]
    assert check.to_json()["stable_rpm"] == [13400.0, 15100.0] and unbounded.to_json()["stable_rpm"] is None
    assert list(unbounded.to_columns())[-3:] == [
        "stability_text",
        "stability_stable_rpm_low",
        "stability_stable_rpm_high",
    ]
    assert unbounded.to_columns()["stability_stable_rpm_low"] is None
    assert check.to_columns()["stability_stable_rpm_high"] == 15100.0
