"""A scenario assembled into what a run takes: the machine built, the controllers designed, the
reference planned, the drive, the encoders, the disturbances and, for a part program, the program
as planned before the run (with a stock its cut); every cross-field constraint checked, each
error naming its field."""

from __future__ import annotations

import warnings
from contextlib import contextmanager
from dataclasses import dataclass, replace

import numpy as np

from controllers import CONTROLLERS, OBSERVERS
from controllers.blocks import Controller, with_correction
from controllers.registry import Context, ParameterError, build_controller, make_observers
from twin.disturbances import DISTURBANCES
from twin.errors import TwinInputError
from twin.machines import BuiltMachine, build
from twin.machining.program_cut import program_milling
from twin.outcome import PlannedProgram, planned_program
from twin.references import REFERENCES, ReferenceContext
from twin.references.gcode import GcodeReference, StreamedGcodeReference
from twin.scenario.schema import ControllerSpec, Scenario
from twin.sim.drive import Drive, Encoder, substeps_per_tick
from twin.sim.protocols import Disturbance, Reference
from twin.sim.runner import MAX_PHYSICS_STEPS, RunResult, simulate


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


def _controller(spec: ControllerSpec, field: str, base: Context) -> Controller:
    """Build one controller entry for the axes of ``base`` (period, plants, delay); errors name
    ``<field>.<what>``."""
    CONTROLLERS.lookup(spec.type, field=f"{field}.type", error=TwinInputError)
    if (spec.type == "sum") != (spec.parts is not None):
        raise TwinInputError(
            f"{field}.parts", [p.type for p in spec.parts or []], "give parts for type 'sum', and only there"
        )
    parts = [_controller(p, f"{field}.parts.{i}", base) for i, p in enumerate(spec.parts or [])]
    ctx = replace(base, method=spec.discretization, parts=parts)
    try:
        with _design_warnings_as_errors():
            ctrl = build_controller(
                spec.type, spec.params, ctx, velocity_ff=spec.velocity_ff, acceleration_ff=spec.acceleration_ff
            )
    except ParameterError as exc:
        raise TwinInputError(f"{field}.params.{exc.field}", exc.value, exc.reason) from None
    except (ValueError, KeyError, TypeError, RuntimeWarning) as exc:
        raise TwinInputError(f"{field}.params", spec.params, _design_failure(exc)) from None
    if spec.observer is None:
        return ctrl
    OBSERVERS.lookup(spec.observer.type, field=f"{field}.observer.type", error=TwinInputError)
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
        return DISTURBANCES[spec.type].value(spec, axis_names, seed, field)
    except TwinInputError as exc:
        name = exc.field.removeprefix("disturbance.")
        if name.startswith(field):
            raise
        raise TwinInputError(f"{field}.{name}", exc.value, exc.reason) from None


@dataclass
class RunInputs:
    """Everything :func:`twin.sim.runner.simulate` takes, assembled from a scenario (see its
    parameters); with a stock, the reference is the program cutting it.  For a part program,
    ``program`` is the program as planned before the run, what :func:`twin.outcome.finish`
    reads after it (None for other references)."""

    machine: BuiltMachine
    controllers: list[Controller]
    reference: Reference
    duration_s: float
    control_period_s: float
    drive: Drive
    encoder: Encoder
    record_every: int | None
    disturbances: list[Disturbance]
    program: PlannedProgram | None = None

    def simulate(
        self,
        *,
        duration_s: float | None = None,
        progress: bool | None = None,
        compiled: bool | None = None,
        max_physics_steps: int = MAX_PHYSICS_STEPS,
    ) -> RunResult:
        """The run (:func:`twin.sim.runner.simulate`), for ``duration_s`` if given (s) instead of
        the scenario's."""
        return simulate(
            self.machine,
            self.controllers,
            self.reference,
            self.duration_s if duration_s is None else duration_s,
            self.control_period_s,
            drive=self.drive,
            encoder=self.encoder,
            disturbances=self.disturbances,
            record_every=self.record_every,
            progress=progress,
            compiled=compiled,
            max_physics_steps=max_physics_steps,
        )


def assemble(scn: Scenario) -> RunInputs:
    """Build everything a run of ``scn`` needs, checking the constraints between its fields.

    Raises
    ------
    TwinInputError
        The first field that does not fit (a controller a design cannot make, a stock without a
        program, a disturbance's bad value, ...), named.
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
    diameters = {t.number: t.diameter_mm for t in scn.tools if t.number is not None}
    reference = REFERENCES[scn.reference.type].value(
        scn.reference,
        ReferenceContext(
            names,
            machine,
            scn.planner,
            numbers,
            scn.stock is not None,
            saturation_V=scn.drive.saturation_V,
            tool_diameters_mm=diameters,
        ),
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
    program = None
    if scn.stock is not None and not isinstance(reference, GcodeReference):
        raise TwinInputError(
            "stock", "...", f"a stock is cut by a G-code program, not a {scn.reference.type} reference"
        )
    if isinstance(reference, GcodeReference) and scn.stock is not None:
        cut = program_milling(reference.plan, scn.stock, scn.tool, scn.tools, scn.seed)
        reference = reference.cutting(cut)
        disturbances.append(cut.milling)
        program = planned_program(reference.checks, reference.plan, cut, scn.stock, tuple(scn.inspect))
    elif isinstance(reference, GcodeReference):
        program = planned_program(reference.checks, reference.plan)
    elif isinstance(reference, StreamedGcodeReference):
        program = planned_program(reference.checks, None)
    return RunInputs(
        machine=machine,
        controllers=ctrls,
        reference=reference,
        duration_s=duration_s,
        control_period_s=scn.control_period_s,
        drive=drive,
        encoder=encoder,
        record_every=scn.record_every_ticks,
        disturbances=disturbances,
        program=program,
    )
