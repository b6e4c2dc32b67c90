"""Running a scenario: its run, and with a stock the part the actual motion cut and its
inspected features."""

from __future__ import annotations

import numpy as np

from twin.machining.engagement import StockSpec
from twin.machining.inspection import measure, not_found
from twin.machining.part import MachinedPart, virtual_part
from twin.machining.sweep import ToolSweep
from twin.records import Inspected
from twin.scenario.assembly import assemble
from twin.scenario.schema import Scenario
from twin.sim.runner import MAX_PHYSICS_STEPS, RunResult


def run_scenario(scn: Scenario, progress: bool | None = None, max_physics_steps: int = MAX_PHYSICS_STEPS) -> RunResult:
    """Assemble and run a scenario (see :func:`twin.sim.runner.simulate`); with a stock, the part
    the run cut and its inspected features."""
    inputs = assemble(scn)
    result = inputs.simulate(progress=progress, max_physics_steps=max_physics_steps)
    cut_part(result, inputs.reference, scn)
    return result


def cut_part(result: RunResult, reference, scn: Scenario) -> None:
    """With a stock: the part a run's actual motion cut (``result.part``) and its inspected
    features (``result.inspection``); the run's ``reference`` is its program's."""
    if scn.stock is not None and result.program is not None and len(result.t_s):
        result.part = _machined_part(result, result.program.lines, reference, scn.stock)
        result.inspection = [_inspect(f, result.part, scn.stock) for f in scn.inspect]


def _inspect(feature, part: MachinedPart, stock: StockSpec) -> Inspected:
    """A feature measured on the actual part at its height, or why it cannot be."""
    if not stock.bottom_mm <= feature.z_mm <= stock.top_mm:
        return not_found(
            feature, f"z_mm {feature.z_mm:g} is outside the stock (Z {stock.bottom_mm:g} to {stock.top_mm:g} mm)"
        )
    return measure(feature, part)


def _machined_part(result: RunResult, lines: np.ndarray, reference, stock: StockSpec) -> MachinedPart:
    """The part the run's actual motion cut: the table's measured path at the recorded ticks,
    the planned Z and the tool of the planned sample at each tick (its program ``lines``); against
    the nominal part of the program (the ``reference`` cutting the stock) as far as the run went
    (a run stopped before the program's end, by its duration or a divergence, is compared with
    what the program had cut by then, not with material it never reached)."""
    plan = reference.plan
    full = ToolSweep.planned(plan, reference.cut)
    k = np.clip(np.rint(result.t_s / plan.period_s).astype(int), 0, len(full.line) - 1)
    reached = slice(0, int(k[-1]) + 1 if k.size else 0)
    nominal = ToolSweep(
        full.xy_mm[reached], full.tip_mm[reached], full.radius_mm[reached], full.corner_mm[reached], full.line[reached]
    )
    actual = ToolSweep(
        result.table_position_m()[:, :2] * 1e3,
        nominal.tip_mm[k],
        nominal.radius_mm[k],
        nominal.corner_mm[k],
        lines,
    )
    return virtual_part(stock, nominal, actual)
