"""Scenario files (TOML), validated with pydantic, and running them.

A scenario names a machine (with parameter overrides by the source's symbols), a controller
per axis (or one for all axes), a reference, the rates, the drive and sensor settings and a
seed.  See the README for the format; bundled scenarios live in ``twin/scenarios/``.
"""

from __future__ import annotations

import tomllib
from importlib import resources
from pathlib import Path
from typing import Annotated, Literal, Union

import numpy as np
from pydantic import BaseModel, ConfigDict, Field, PositiveFloat, ValidationError

from controllers import CONTROLLERS, make_controller
from twin.drive import Drive, Encoder, substeps_per_tick
from twin.errors import TwinInputError
from twin.machines import build
from twin.references import Circle, Polyline, Ramp, Step, SumOfSines, square
from twin.runner import RunResult, simulate


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid")


class ControllerSpec(_Strict):
    """One controller: a registry name, its parameters, discretization and feedforward."""

    type: str
    params: dict[str, float | list[float]] = {}
    discretization: Literal["tustin", "zoh"] = "tustin"
    velocity_ff: float = Field(0.0, description="V per m/s of reference velocity")
    acceleration_ff: float = Field(0.0, description="V per m/s^2 of reference acceleration")


class StepRef(_Strict):
    type: Literal["step"]
    amplitude_m: float
    t0_s: float = 0.0
    axes: list[str] | None = None


class RampRef(_Strict):
    type: Literal["ramp"]
    rate_m_per_s: float
    t0_s: float = 0.0
    axes: list[str] | None = None


class SinesRef(_Strict):
    type: Literal["sines"]
    amplitudes_m: list[float]
    frequencies_hz: list[PositiveFloat]
    phases_rad: list[float] | None = None
    axes: list[str] | None = None


class CircleRef(_Strict):
    type: Literal["circle"]
    radius_mm: PositiveFloat
    feed_mm_per_min: PositiveFloat


class SquareRef(_Strict):
    type: Literal["square"]
    side_mm: PositiveFloat
    feed_mm_per_min: PositiveFloat


class PolylineRef(_Strict):
    type: Literal["polyline"]
    points_mm: list[tuple[float, float]]
    feed_mm_per_min: PositiveFloat


ReferenceSpec = Annotated[Union[StepRef, RampRef, SinesRef, CircleRef, SquareRef, PolylineRef],
                          Field(discriminator="type")]


class DriveSpec(_Strict):
    saturation_V: PositiveFloat | None = None
    delay_s: float | None = Field(None, ge=0, description="default: the machine's delay")


class SensorSpec(_Strict):
    encoder_resolution_m: float | list[float] = Field(0.0, description="0 for ideal")
    noise_std_m: float | list[float] = 0.0


class Scenario(_Strict):
    """A closed-loop run; every field in SI unless its name says otherwise."""

    name: str = "scenario"
    description: str = ""
    machine: str
    overrides: dict[str, float] = {}
    duration_s: PositiveFloat
    timestep_s: PositiveFloat = 1e-4
    control_period_s: PositiveFloat = 1e-3
    seed: int = 0
    controller: ControllerSpec | None = None
    controllers: dict[str, ControllerSpec] | None = None
    reference: ReferenceSpec
    drive: DriveSpec = DriveSpec()
    sensors: SensorSpec = SensorSpec()


def _first_error(err: ValidationError) -> TwinInputError:
    e = err.errors()[0]
    field = ".".join(str(p) for p in e["loc"]) or "scenario"
    return TwinInputError(field, e.get("input"), e["msg"])


def bundled_scenarios() -> dict[str, Path]:
    """Bundled scenario files by name (file stem)."""
    folder = resources.files("twin") / "scenarios"
    return {Path(p.name).stem: Path(str(p)) for p in folder.iterdir() if p.name.endswith(".toml")}


def load_scenario(source: str | Path) -> Scenario:
    """Read and validate a scenario from a file path or a bundled scenario name.

    Raises
    ------
    TwinInputError
        Missing file, malformed TOML, or an invalid field (named in the message).
    """
    path = Path(source)
    if not path.exists():
        bundled = bundled_scenarios()
        if str(source) not in bundled:
            raise TwinInputError("scenario", str(source),
                                 f"no such file or bundled scenario (bundled: {', '.join(sorted(bundled))})")
        path = bundled[str(source)]
    try:
        data = tomllib.loads(path.read_text())
    except tomllib.TOMLDecodeError as exc:
        raise TwinInputError("scenario file", str(path), f"malformed TOML: {exc}") from None
    return scenario_from_dict(data)


def scenario_from_dict(data: dict) -> Scenario:
    """Validate a scenario given as a dict (as parsed from TOML)."""
    try:
        return Scenario.model_validate(data)
    except ValidationError as exc:
        raise _first_error(exc) from None


def _per_axis(value, n_axes: int, field: str) -> np.ndarray:
    arr = np.broadcast_to(np.asarray(value, float), (n_axes,)) if np.ndim(value) == 0 else np.asarray(value, float)
    if arr.shape != (n_axes,):
        raise TwinInputError(field, value, f"give one value or one per axis ({n_axes})")
    return arr


def _reference(spec, axis_names: list[str]):
    n = len(axis_names)

    def axes_idx(names):
        if names is None:
            return None
        for a in names:
            if a not in axis_names:
                raise TwinInputError("reference.axes", a, f"machine axes are {axis_names}")
        return tuple(axis_names.index(a) for a in names)

    if isinstance(spec, (CircleRef, SquareRef, PolylineRef)) and n != 2:
        raise TwinInputError("reference.type", spec.type, f"a 2-D path needs two axes, the machine has {n}")
    if isinstance(spec, StepRef):
        return Step(spec.amplitude_m, spec.t0_s, n, axes_idx(spec.axes))
    if isinstance(spec, RampRef):
        return Ramp(spec.rate_m_per_s, spec.t0_s, n, axes_idx(spec.axes))
    if isinstance(spec, SinesRef):
        if len(spec.amplitudes_m) != len(spec.frequencies_hz):
            raise TwinInputError("reference.frequencies_hz", spec.frequencies_hz,
                                 "needs as many entries as amplitudes_m")
        return SumOfSines(tuple(spec.amplitudes_m), tuple(spec.frequencies_hz),
                          tuple(spec.phases_rad) if spec.phases_rad else None, n, axes_idx(spec.axes))
    if isinstance(spec, CircleRef):
        return Circle(spec.radius_mm, spec.feed_mm_per_min)
    if isinstance(spec, SquareRef):
        return square(spec.side_mm, spec.feed_mm_per_min)
    try:
        return Polyline([tuple(p) for p in spec.points_mm], spec.feed_mm_per_min)
    except ValueError as exc:
        raise TwinInputError("reference.points_mm", spec.points_mm, str(exc)) from None


def _controller(spec: ControllerSpec, dt: float, field: str):
    if spec.type not in CONTROLLERS:
        raise TwinInputError(f"{field}.type", spec.type, f"unknown controller (known: {', '.join(CONTROLLERS)})")
    try:
        return make_controller(spec.type, dt, spec.params, spec.discretization, spec.velocity_ff,
                               spec.acceleration_ff)
    except (ValueError, KeyError, TypeError) as exc:
        raise TwinInputError(f"{field}.params", spec.params, str(exc)) from None


def prepare(scn: Scenario):
    """Build everything a run needs, validating cross-field constraints.

    Returns
    -------
    dict
        Keyword arguments for :func:`twin.runner.simulate` plus ``machine``.
    """
    machine = build(scn.machine, scn.overrides, scn.timestep_s)
    names = [a.name for a in machine.axes]
    substeps = substeps_per_tick(scn.control_period_s, scn.timestep_s)
    if (scn.controller is None) == (scn.controllers is None):
        raise TwinInputError("controller", None, "give either [controller] (all axes) or [controllers.<axis>]")
    if scn.controllers is not None:
        missing = [a for a in names if a not in scn.controllers]
        unknown = [a for a in scn.controllers if a not in names]
        if unknown or missing:
            raise TwinInputError("controllers", sorted(scn.controllers), f"need exactly the axes {names}")
        ctrls = [_controller(scn.controllers[a], scn.control_period_s, f"controllers.{a}") for a in names]
    else:
        ctrls = [_controller(scn.controller, scn.control_period_s, "controller") for _ in names]
    delay = machine.delay_s if scn.drive.delay_s is None else scn.drive.delay_s
    drive = Drive(len(names), substeps, scn.timestep_s, delay, scn.drive.saturation_V)
    encoder = Encoder(_per_axis(scn.sensors.encoder_resolution_m, len(names), "sensors.encoder_resolution_m"),
                      _per_axis(scn.sensors.noise_std_m, len(names), "sensors.noise_std_m"),
                      np.array(machine.sensor_gains), scn.seed)
    return {"machine": machine, "controllers": ctrls, "reference": _reference(scn.reference, names),
            "duration_s": scn.duration_s, "control_period_s": scn.control_period_s,
            "drive": drive, "encoder": encoder}


def run_scenario(scn: Scenario, progress: bool | None = None) -> RunResult:
    """Validate and run a scenario."""
    kwargs = prepare(scn)
    return simulate(kwargs.pop("machine"), **kwargs, progress=progress)
