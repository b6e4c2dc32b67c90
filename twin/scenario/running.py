"""Running a scenario, one way down: assembled (with a part program, planned and cut before
the run), run, and finished from the run's motion (the part it cut, its inspection, the
program's warnings: :func:`twin.outcome.finish`)."""

from __future__ import annotations

from twin.errors import RunInterrupted, SimulationDiverged
from twin.outcome import RunOutcome, finish
from twin.scenario.assembly import assemble
from twin.scenario.schema import Scenario
from twin.sim.runner import MAX_PHYSICS_STEPS


def run_scenario(
    scn: Scenario,
    progress: bool | None = None,
    max_physics_steps: int = MAX_PHYSICS_STEPS,
    *,
    keep_partial: bool = False,
) -> RunOutcome:
    """Assemble and run a scenario (see :func:`twin.sim.runner.simulate`); its outcome: the run,
    and with a part program its warnings, with a stock the part the run cut and its inspected
    features.

    Parameters
    ----------
    keep_partial : bool
        On divergence or Ctrl-C, the outcome of the run up to there (its ``stopped`` the error,
        no part) instead of raising.

    Raises
    ------
    TwinInputError
        Bad input, before anything runs.
    SimulationDiverged, RunInterrupted
        Unless ``keep_partial`` (and always where the run computed nothing).
    """
    inputs = assemble(scn)
    try:
        run = inputs.simulate(progress=progress, max_physics_steps=max_physics_steps)
    except (SimulationDiverged, RunInterrupted) as exc:
        if not keep_partial or exc.result is None:
            raise
        return finish(exc.result, inputs.program, exc)
    return finish(run, inputs.program)
