"""Scenario files (TOML), validated with pydantic, assembled and run.

A scenario names a machine (with parameter overrides by the source's symbols), a controller per
axis (or one for all axes), a reference, the rates, the drive and sensor settings and a seed.  See
the README for the format; bundled scenarios live in ``twin/scenarios/``.

The package in four modules: :mod:`~twin.scenario.schema` (the fields),
:mod:`~twin.scenario.files` (reading and validating a file, with settings),
:mod:`~twin.scenario.assembly` (the run's inputs built from it, a part program planned and cut
before the run) and :mod:`~twin.scenario.running` (the run and its outcome,
:class:`twin.outcome.RunOutcome`).
"""

from twin.scenario.assembly import RunInputs, assemble
from twin.scenario.files import bundled_scenarios, load_scenario, read_scenario_data, scenario_from_dict
from twin.scenario.running import run_scenario
from twin.scenario.schema import (
    MAX_TIMESTEP_S,
    MIN_TIMESTEP_S,
    ControllerSpec,
    DriveSpec,
    ObserverSpec,
    Scenario,
    SensorSpec,
)

__all__ = [
    "MAX_TIMESTEP_S",
    "MIN_TIMESTEP_S",
    "ControllerSpec",
    "DriveSpec",
    "ObserverSpec",
    "RunInputs",
    "Scenario",
    "SensorSpec",
    "assemble",
    "bundled_scenarios",
    "load_scenario",
    "read_scenario_data",
    "run_scenario",
    "scenario_from_dict",
]
