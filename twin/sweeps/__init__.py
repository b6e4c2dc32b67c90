"""Monte Carlo and parameter sweeps of a scenario on Dask (:mod:`.plan` draws the samples,
:mod:`.run` runs them and streams Parquet, :mod:`.summary` reports them) and sweep files."""

from __future__ import annotations

import os
import tomllib
from dataclasses import dataclass

from pydantic import BaseModel, ConfigDict, Field, ValidationError

from twin.errors import input_file
from twin.sampling import SamplePlan, parse_variation
from twin.spec import validation_error


class SweepFile(BaseModel):
    """A sweep file (TOML): the scenario, what to vary and how many samples."""

    model_config = ConfigDict(extra="forbid")
    scenario: str = Field(description="bundled scenario name or scenario TOML file (relative to the sweep file)")
    vary: dict[str, str] = Field(description="PATH = SPEC, e.g. 'overrides.m_x' = 'box'")
    set: list[str] = Field([], description="PATH=VALUE settings of the scenario, as twin run --set")
    samples: int = 100
    seed: int = 0
    latin_hypercube: bool = False
    batch_size: int = 10
    out: str | None = None


def sweep_spec(target: str) -> SweepFile:
    """The sweep ``target`` names: a sweep file (a TOML file with a ``vary`` table) read and
    validated, its ``scenario`` path made relative to it; anything else is a scenario (bundled
    name or file) with nothing varied yet.

    Raises
    ------
    TwinInputError
        A sweep file with an invalid field (named).
    """
    if not target.endswith(".toml"):
        return SweepFile(scenario=target, vary={})
    path = input_file(target, "scenario")
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8"))
    except (tomllib.TOMLDecodeError, UnicodeDecodeError):
        return SweepFile(scenario=target, vary={})  # the scenario loader reports what is wrong with it
    if "vary" not in data:
        return SweepFile(scenario=target, vary={})
    try:
        spec = SweepFile(**data)
    except ValidationError as exc:
        raise validation_error(exc, data) from None
    candidate = path.parent / spec.scenario
    if candidate.suffix == ".toml" and os.path.isfile(candidate):
        spec.scenario = str(candidate)
    return spec


@dataclass
class SweepSpec:
    """Everything a sweep needs: the scenario as a dict, its name, machine and controller type,
    the machine's axes and the :class:`SamplePlan`."""

    scenario: dict
    name: str
    machine: str
    controller: str | None
    axes: tuple[str, ...]
    plan: SamplePlan


def prepare_sweep(
    scenario: str, *, settings: dict, vary: list[str], samples: int, seed: int, latin_hypercube: bool
) -> SweepSpec:
    """Load and check the scenario with ``settings`` (``{dotted path: value}``, once, before any
    sample runs) and build the plan.

    Raises
    ------
    TwinInputError
        An invalid scenario, setting or variation, or a varied path that does not lead into
        the scenario.  Varied values the scenario rejects are not errors here: those samples
        become ``error`` rows.
    """
    from twin.machines import get_machine
    from twin.scenario import assemble, read_scenario_data, scenario_from_dict
    from twin.settings import set_fields
    from twin.sweeps.run import scenario_value

    data = set_fields(read_scenario_data(scenario), settings, "--set ")
    scn = scenario_from_dict(data)
    plan = SamplePlan(
        [parse_variation(v, get_machine(scn.machine).parameters) for v in vary], samples, seed, latin_hypercube
    )
    checked = assemble(scn)
    # the varied paths lead into the scenario (a value the scenario rejects is that sample's error row)
    set_fields(data, {p: scenario_value(v) for p, v in plan.values(0).items()}, "--vary ")
    controller = scn.controller.type if scn.controller is not None else None
    return SweepSpec(data, scn.name, scn.machine, controller, tuple(a.name for a in checked.machine.axes), plan)
