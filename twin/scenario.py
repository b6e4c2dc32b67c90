"""Scenario files (TOML), validated with pydantic, and running them.

A scenario names a machine (with parameter overrides by the source's symbols), a controller
per axis (or one for all axes), a reference, the rates, the drive and sensor settings and a
seed.  See the README for the format; bundled scenarios live in ``twin/scenarios/``.
"""

from __future__ import annotations

import copy
import tomllib
import warnings
from contextlib import contextmanager
from dataclasses import replace
from importlib import resources
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any, Literal

import numpy as np
from pydantic import Field, PositiveFloat, ValidationError

from controllers import CONTROLLERS, OBSERVERS, make_controller
from controllers.blocks import with_correction
from controllers.registry import Context, ParameterError, make_observers
from twin.errors import TwinInputError, input_file
from twin.gcode.planner import PlannerSettings
from twin.machines import build, is_machine_file
from twin.process import DISTURBANCES, DisturbanceSpecBase
from twin.process.inspection import InspectSpec, measure, not_found
from twin.process.machining import StockSpec, ToolSpec, program_milling
from twin.process.part import MachinedPart, SectionTooComplex, Sweep, machined_part
from twin.process.part_map import part_map
from twin.references import REFERENCES, ReferenceContext, ReferenceSpecBase
from twin.sim.drive import Drive, Encoder, substeps_per_tick
from twin.sim.runner import MAX_PHYSICS_STEPS, RunResult, simulate
from twin.spec import StrictSpec, read_toml, tagged_union, validation_error


class ObserverSpec(StrictSpec):
    """An observer add-on: a kind of ``controllers.OBSERVERS`` and its parameters (checked by
    the kind's own model)."""

    type: str
    params: dict[str, Any] = Field(default_factory=dict)


class ControllerSpec(StrictSpec):
    """One controller: a kind of ``controllers.CONTROLLERS``, its parameters (checked by the
    kind's own model), discretization, feedforward, an optional observer add-on and, for
    ``type = "sum"``, its parts."""

    type: str
    params: dict[str, Any] = Field(default_factory=dict)
    discretization: Literal["tustin", "zoh"] = "tustin"
    velocity_ff: float = Field(0.0, description="V per m/s of reference velocity")
    acceleration_ff: float = Field(0.0, description="V per m/s^2 of reference acceleration")
    observer: ObserverSpec | None = None
    parts: list[ControllerSpec] | None = Field(None, description="the summed controllers of type 'sum'")


#: The ``[reference]`` table: one spec per registered kind (:mod:`twin.references`), told apart by
#: ``type``; to a type checker, which cannot follow a union built at run time, the kinds' base.
if TYPE_CHECKING:
    ReferenceSpec = ReferenceSpecBase
else:
    ReferenceSpec = tagged_union(REFERENCES)


class DriveSpec(StrictSpec):
    saturation_V: PositiveFloat | None = None
    delay_s: float | None = Field(None, ge=0, le=10.0, description="default: the machine's delay; at most 10 s")


#: A sensor's resolution or noise at most (m): coarser than any scale or encoder of a machine tool.
MAX_SENSOR_M = 1e-3
#: A resolution or a noise's standard deviation (m), in [0, MAX_SENSOR_M].
SensorMetres = Annotated[float, Field(ge=0, le=MAX_SENSOR_M)]


class SensorSpec(StrictSpec):
    encoder_resolution_m: SensorMetres | list[SensorMetres] | None = Field(
        None, description="the table's scale, m; 0 for ideal; default: the machine's (0 for the papers' machines)"
    )
    motor_encoder_resolution_m: SensorMetres | list[SensorMetres] | None = Field(
        None, description="the motor's encoder in table travel, m; 0 for ideal; default: the machine's"
    )
    noise_std_m: SensorMetres | list[SensorMetres] = 0.0
    velocity: Literal["backward_difference", "tachometer"] = "backward_difference"
    feedback: Literal["dual", "table", "motor"] | None = Field(
        None,
        description="position on the table's scale and velocity on the motor's encoder (dual), both on the "
        "scale (table) or both on the motor (motor, a semi-closed loop); default: the machine's (dual for a "
        "machine file, table for the papers' machines)",
    )


#: The ``[[disturbances]]`` entries: one spec per registered kind (:mod:`twin.process`), the same way.
if TYPE_CHECKING:
    DisturbanceSpec = DisturbanceSpecBase
else:
    DisturbanceSpec = tagged_union(DISTURBANCES)


#: Shortest physics step (s): 0.1 us, a thousand times finer than any mode of these drives needs.
MIN_TIMESTEP_S = 1e-7
#: Longest physics step (s): 10 ms, the order of the fastest mechanical time constants here.
MAX_TIMESTEP_S = 1e-2
#: Longest control period (s).
MAX_CONTROL_PERIOD_S = 1.0
#: ``[[inspect]]`` features at most.
MAX_FEATURES = 100


class Scenario(StrictSpec):
    """A closed-loop run; every field in SI unless its name says otherwise."""

    name: str = "scenario"
    description: str = ""
    machine: str
    overrides: dict[str, float] = Field(default_factory=dict)
    duration_s: PositiveFloat | None = Field(
        None, description="simulated time, s; default the reference's own end (a G-code program's cycle time)"
    )
    timestep_s: float | None = Field(
        None,
        ge=MIN_TIMESTEP_S,
        le=MAX_TIMESTEP_S,
        description="physics step, s; default the machine's (0.1 ms for the papers')",
    )
    control_period_s: float = Field(1e-3, ge=MIN_TIMESTEP_S, le=MAX_CONTROL_PERIOD_S)
    seed: int = Field(0, ge=0)
    record_every_ticks: int | None = Field(
        None, ge=0, description="record every Nth tick; 0: metrics only; default every tick up to 100 000 ticks"
    )
    controller: ControllerSpec | None = None
    controllers: dict[str, ControllerSpec] | None = None
    reference: ReferenceSpec
    drive: DriveSpec = DriveSpec()
    sensors: SensorSpec = SensorSpec()
    disturbances: list[DisturbanceSpec] = Field(default_factory=list)
    planner: PlannerSettings = PlannerSettings()
    stock: StockSpec | None = Field(None, description="a workpiece the G-code program cuts")
    tool: ToolSpec | None = Field(None, description="the cutter of a program without T words")
    tools: list[ToolSpec] = Field(default_factory=list, description="the cutters of a program, by T number")
    inspect: list[InspectSpec] = Field(
        default_factory=list, max_length=MAX_FEATURES, description="features of the part measured on the virtual part"
    )


def bundled_scenarios() -> dict[str, Path]:
    """Bundled scenario files by name (file stem)."""
    folder = resources.files("twin") / "scenarios"
    return {Path(p.name).stem: Path(str(p)) for p in folder.iterdir() if p.name.endswith(".toml")}


def parse_settings(settings: list[str]) -> dict:
    """``PATH=VALUE`` strings (``disturbances.0.spindle_rpm=2500``) as ``{path: value}``:
    ``VALUE`` is a TOML value (``2500``, ``[0.02]``, ``"down"``; a bare word counts as a string).

    Raises
    ------
    TwinInputError
        A malformed setting.
    """
    values = {}
    for item in settings:
        path, sep, text = item.partition("=")
        if not sep or not all(path.strip().split(".")):
            raise TwinInputError("--set", item, "use PATH=VALUE, e.g. disturbances.0.spindle_rpm=2500")
        try:
            values[path.strip()] = tomllib.loads(f"v = {text}")["v"]
        except tomllib.TOMLDecodeError:
            values[path.strip()] = text.strip()
    return values


def apply_settings(data: dict, settings: list[str]) -> dict:
    """A deep copy of ``data`` with ``PATH=VALUE`` settings applied (:func:`parse_settings`,
    :func:`set_fields`).

    Raises
    ------
    TwinInputError
        A malformed setting or a path that does not lead into the scenario.
    """
    return set_fields(data, parse_settings(settings), "--set ")


def set_fields(data: dict, values: dict, label: str = "") -> dict:
    """A deep copy of ``data`` with each dotted ``path`` of ``values`` set to its value (list
    entries by index; missing tables are created).

    Raises
    ------
    TwinInputError
        A path that does not lead into the scenario (named with ``label`` before it).
    """
    out = copy.deepcopy(data)
    for path, value in values.items():
        keys = str(path).split(".")
        if not all(keys):
            raise TwinInputError(f"{label}{path}", value, "not a dotted path, e.g. disturbances.0.spindle_rpm")
        node = out
        for depth, key in enumerate(keys):
            last = depth == len(keys) - 1
            if isinstance(node, list):
                if not (key.isdigit() and int(key) < len(node)):
                    raise TwinInputError(f"{label}{path}", key, f"not an index of a list of {len(node)}")
                key = int(key)
            elif not isinstance(node, dict):
                raise TwinInputError(f"{label}{path}", key, "goes below a value")
            if last:
                node[key] = copy.deepcopy(value)
            else:
                if isinstance(node, dict) and key not in node:
                    node[key] = {}
                node = node[key]
    return out


def read_scenario_data(source: str | Path) -> dict:
    """A scenario file or bundled scenario as the dict its TOML holds (not yet validated).

    Raises
    ------
    TwinInputError
        Missing file, malformed TOML, or a file that is not UTF-8 text.
    """
    bundled = bundled_scenarios()
    missing = f"no such file or bundled scenario (bundled: {', '.join(sorted(bundled))})"
    path = bundled[str(source)] if str(source) in bundled else input_file(source, "scenario", missing)
    return _relative_to(read_toml(path, "scenario file"), path.parent)


def _relative_to(data: dict, folder: Path) -> dict:
    """``data`` with its file fields (a machine file, the reference's ``relative_paths``) made
    relative to the scenario file's ``folder`` where they are relative paths."""
    machine = data.get("machine")
    if isinstance(machine, str) and is_machine_file(machine) and not Path(machine).is_absolute():
        data["machine"] = str(folder / machine)
    reference = data.get("reference")
    if isinstance(reference, dict) and isinstance(reference.get("type"), str) and reference["type"] in REFERENCES:
        for key in getattr(REFERENCES[reference["type"]].spec, "relative_paths", ()):
            value = reference.get(key)
            if isinstance(value, str) and not Path(value).is_absolute():
                reference[key] = str(folder / value)
    return data


def load_scenario(source: str | Path, settings: list[str] | None = None) -> Scenario:
    """Read and validate a scenario from a file path or a bundled scenario name.

    ``settings`` (``PATH=VALUE``) change fields before validation; see :func:`apply_settings`.

    Raises
    ------
    TwinInputError
        Missing file, malformed TOML, or an invalid field (named in the message).
    """
    return scenario_from_dict(apply_settings(read_scenario_data(source), settings or []))


def scenario_from_dict(data: dict) -> Scenario:
    """Validate a scenario given as a dict (as parsed from TOML)."""
    try:
        return Scenario.model_validate(data)
    except ValidationError as exc:
        raise validation_error(exc) from None


def _per_axis(value, n_axes: int, field: str) -> np.ndarray:
    arr = np.broadcast_to(np.asarray(value, float), (n_axes,)) if np.ndim(value) == 0 else np.asarray(value, float)
    if arr.shape != (n_axes,):
        raise TwinInputError(field, value, f"give one value or one per axis ({n_axes})")
    return arr


@contextmanager
def _design_warnings_as_errors():
    """Run a design procedure with its numerical warnings (numpy's overflow or invalid value,
    scipy's poor convergence) raised as errors: for a user a design that warns has failed, and a
    warning printed before the error line would be a second line."""
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        yield


def _design_failure(exc: Exception) -> str:
    """The reason a controller or observer design failed, for its error line."""
    if isinstance(exc, RuntimeWarning):
        return f"the design failed numerically ({exc})"
    return str(exc)


def _controller(spec: ControllerSpec, field: str, base: Context):
    """Build one controller entry for the axes of ``base`` (period, plants, delay); errors name
    ``<field>.<what>``."""
    if spec.type not in CONTROLLERS:
        raise TwinInputError(f"{field}.type", spec.type, f"unknown controller (known: {', '.join(CONTROLLERS)})")
    if (spec.type == "sum") != (spec.parts is not None):
        raise TwinInputError(
            f"{field}.parts", [p.type for p in spec.parts or []], "give parts for type 'sum', and only there"
        )
    parts = [_controller(p, f"{field}.parts.{i}", base) for i, p in enumerate(spec.parts or [])]
    ctx = replace(base, method=spec.discretization)
    try:
        with _design_warnings_as_errors():
            ctrl = make_controller(
                spec.type,
                ctx.dt,
                spec.params,
                method=ctx.method,
                velocity_ff=spec.velocity_ff,
                acceleration_ff=spec.acceleration_ff,
                axes=ctx.axes,
                plants=ctx.plants,
                parts=parts,
                delay_s=ctx.delay_s,
            )
    except ParameterError as exc:
        raise TwinInputError(f"{field}.params.{exc.field}", exc.value, exc.reason) from None
    except (ValueError, KeyError, TypeError, RuntimeWarning) as exc:
        raise TwinInputError(f"{field}.params", spec.params, _design_failure(exc)) from None
    if spec.observer is None:
        return ctrl
    if spec.observer.type not in OBSERVERS:
        raise TwinInputError(
            f"{field}.observer.type", spec.observer.type, f"unknown observer (known: {', '.join(OBSERVERS)})"
        )
    try:
        with _design_warnings_as_errors():
            observers = make_observers(spec.observer.type, spec.observer.params, ctx)
    except ParameterError as exc:
        raise TwinInputError(f"{field}.observer.params.{exc.field}", exc.value, exc.reason) from None
    except (ValueError, KeyError, TypeError, RuntimeWarning) as exc:
        raise TwinInputError(f"{field}.observer.params", spec.observer.params, _design_failure(exc)) from None
    return with_correction(ctrl, observers)


def _disturbance(spec, index: int, axis_names: list[str], seed: int):
    """Build one disturbance by its kind's builder; errors name ``disturbances.<index>.<field>``."""
    field = f"disturbances.{index}"
    seed = seed if getattr(spec, "seed", None) is None else spec.seed
    try:
        return DISTURBANCES[spec.type].build(spec, axis_names, seed, field)
    except TwinInputError as exc:
        name = exc.field.removeprefix("disturbance.")
        if name.startswith(field):
            raise
        raise TwinInputError(f"{field}.{name}", exc.value, exc.reason) from None


def prepare(scn: Scenario):
    """Build everything a run needs, validating cross-field constraints.

    Returns
    -------
    dict
        Keyword arguments for :func:`twin.sim.runner.simulate` plus ``machine``.
    """
    machine = build(scn.machine, scn.overrides, scn.timestep_s)
    names = [a.name for a in machine.axes]
    timestep_s = float(machine.model.opt.timestep)
    substeps = substeps_per_tick(scn.control_period_s, timestep_s)
    delay = machine.delay_s if scn.drive.delay_s is None else scn.drive.delay_s
    base = Context(
        scn.control_period_s, tuple(names), plants={a: machine.plant[i][i] for i, a in enumerate(names)}, delay_s=delay
    )
    if (scn.controller is None) == (scn.controllers is None):
        raise TwinInputError("controller", None, "give either [controller] (all axes) or [controllers.<axis>]")
    if scn.controllers is not None:
        missing = [a for a in names if a not in scn.controllers]
        unknown = [a for a in scn.controllers if a not in names]
        if unknown or missing:
            raise TwinInputError("controllers", sorted(scn.controllers), f"need exactly the axes {names}")
        ctrls = [_controller(scn.controllers[a], f"controllers.{a}", replace(base, axes=(a,))) for a in names]
    elif scn.controller is not None:
        ctrls = [_controller(scn.controller, "controller", base)]
    numbers = frozenset(t.number for t in scn.tools if t.number is not None) if scn.tools else None
    reference = REFERENCES[scn.reference.type].build(
        scn.reference, ReferenceContext(names, machine, scn.planner, numbers, scn.stock is not None)
    )
    duration_s = scn.duration_s if scn.duration_s is not None else getattr(reference, "duration_s", None)
    if duration_s is None:
        raise TwinInputError("duration_s", None, f"give it: a {scn.reference.type} reference has no end of its own")
    drive = Drive(len(names), substeps, timestep_s, delay, scn.drive.saturation_V)

    def resolution(key: str) -> np.ndarray:
        """``sensors.<key>``, or the machine's own where the scenario gives none."""
        given = getattr(scn.sensors, key)
        return _per_axis(list(getattr(machine, key)) if given is None else given, len(names), f"sensors.{key}")

    encoder = Encoder(
        resolution("encoder_resolution_m"),
        _per_axis(scn.sensors.noise_std_m, len(names), "sensors.noise_std_m"),
        np.array(machine.sensor_gains),
        scn.seed,
        scn.sensors.velocity,
        scn.sensors.feedback or machine.feedback,
        resolution("motor_encoder_resolution_m"),
    )
    disturbances = [_disturbance(d, i, names, scn.seed) for i, d in enumerate(scn.disturbances)]
    if scn.inspect and scn.stock is None:
        raise TwinInputError("inspect", scn.inspect[0].name, "features are measured on a part: give [stock]")
    if scn.stock is not None:
        if scn.reference.type != "gcode":
            raise TwinInputError(
                "stock", "...", f"a stock is cut by a G-code program, not a {scn.reference.type} reference"
            )
        cut = program_milling(reference.plan, scn.stock, scn.tool, scn.tools, scn.seed)
        plan = reference.plan
        reference.nominal_sweep = Sweep(
            plan.position[:, :2] * 1e3, plan.position[:, 2] * 1e3, cut.radius_m * 1e3, cut.corner_m * 1e3, plan.line
        )
        reference.engagement, reference.height_map = cut.table, cut.height_map
        reference.warnings, reference.warnings_total = cut.warnings, cut.warnings_total
        disturbances.append(cut.milling)
    return {
        "machine": machine,
        "controllers": ctrls,
        "reference": reference,
        "duration_s": duration_s,
        "control_period_s": scn.control_period_s,
        "drive": drive,
        "encoder": encoder,
        "record_every": scn.record_every_ticks,
        "disturbances": disturbances,
    }


def run_scenario(scn: Scenario, progress: bool | None = None, max_physics_steps: int = MAX_PHYSICS_STEPS) -> RunResult:
    """Validate and run a scenario (see :func:`twin.sim.runner.simulate`)."""
    kwargs = prepare(scn)
    reference = kwargs["reference"]
    result = simulate(kwargs.pop("machine"), **kwargs, progress=progress, max_physics_steps=max_physics_steps)
    if scn.stock is not None and result.program is not None and len(result.t_s):
        result.part = _machined_part(result, result.program.lines, reference, scn.stock)
        result.inspection = [_inspect(f, result.part) for f in scn.inspect]
    return result


def _inspect(feature, part: MachinedPart) -> dict:
    """A feature measured on the actual part's section at its height, or why it cannot be."""
    try:
        return measure(feature, part.actual.section(part.stock, feature.z_mm))
    except SectionTooComplex as exc:
        return not_found(feature, str(exc))


def _machined_part(result: RunResult, lines: np.ndarray, reference, stock: StockSpec) -> MachinedPart:
    """The part the run's actual motion cut: the table's measured path at the recorded ticks,
    the planned Z and the tool of the planned sample at each tick (its program ``lines``); against the nominal part of
    the program as far as the run went (a run stopped before the program's end, by its
    duration or a divergence, is compared with what the program had cut by then, not with
    material it never reached)."""
    k = np.clip(np.rint(result.t_s / reference.plan.period_s).astype(int), 0, len(reference.nominal_sweep.line) - 1)
    reached = slice(0, int(k[-1]) + 1 if k.size else 0)
    full = reference.nominal_sweep
    nominal = Sweep(
        full.xy_mm[reached], full.tip_mm[reached], full.radius_mm[reached], full.corner_mm[reached], full.line[reached]
    )
    actual = Sweep(
        result.table_position_m()[:, :2] * 1e3,
        nominal.tip_mm[k],
        nominal.radius_mm[k],
        nominal.corner_mm[k],
        lines,
    )
    part = machined_part(stock.polygon(), nominal, actual, stock.top_mm, stock.bottom_mm)
    part.maps = part_map(stock, nominal, actual)
    part.floor_error_um = part.maps.floor_error()
    return part
