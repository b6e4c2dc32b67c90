"""The public Python API: what the command line does, from a script.

>>> import twin
>>> run = twin.run("choi1999_mimo_cutting", duration_s=0.5)
>>> run.summary["max_contour_error_um"]          # the CLI's --json summary
>>> frame = run.to_pandas()                        # time-indexed, units in the column names
>>> frame["error/x (µm)"].abs().max()

Settings are keyword arguments with the dotted paths of ``--set``:
``twin.run("slot_linear_motor", **{"disturbances.0.spindle_rpm": 2500})``, or with ``__`` for
each dot (``disturbances__0__spindle_rpm=2500``).  Values are Python values (numbers, strings,
lists, dicts).  Bad input raises :class:`twin.errors.TwinInputError` naming the field; a
diverging run raises :class:`twin.errors.SimulationDiverged` with the simulated time and what
the run computed before it (``exc.result``).
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

from twin.errors import TwinInputError
from twin.reproductions import DEFAULT_SAMPLES, DEFAULT_SEED, DEFAULT_TWIN_SAMPLES
from twin.results import Calibration, Fidelity, Frf, Program, Run, StabilityLobes, Sweep, Tuning

if TYPE_CHECKING:  # the heavy modules load on first use, not with `import twin`
    from twin.scenario import Scenario


def _paths(settings: dict) -> dict:
    """Settings keyed by dotted path (``a__0__b`` becomes ``a.0.b``)."""
    return {key.replace("__", "."): value for key, value in settings.items()}


def load(source: str | Path, **settings: Any) -> Scenario:
    """A validated scenario: a bundled name or a TOML file, with ``settings`` applied.

    Returns
    -------
    twin.scenario.Scenario
        The pydantic model (``.model_dump()`` gives the dict).

    Raises
    ------
    TwinInputError
        Unknown scenario, malformed file, a setting that leads nowhere or an invalid field.
    """
    from twin.scenario import load_scenario

    return load_scenario(source, _paths(settings))


def run(
    scenario,
    *,
    progress: bool | None = False,
    max_physics_steps: int | None = None,
    keep_partial: bool = False,
    **settings,
) -> Run:
    """Run a scenario (a name, a path, or a :func:`load`-ed scenario) with ``settings``.

    Parameters
    ----------
    progress : bool or None
        Show a progress bar (None: on long runs only).
    max_physics_steps : int or None
        Refuse runs longer than this many physics steps (default 20 000 000).
    keep_partial : bool
        On divergence or Ctrl-C, return the partial :class:`Run` (``stopped`` holds the error,
        ``status`` says which) instead of raising.

    Raises
    ------
    TwinInputError
        Bad input, before anything runs.
    SimulationDiverged, RunInterrupted
        Unless ``keep_partial``.
    """
    from twin.scenario import Scenario, run_scenario
    from twin.sim.runner import MAX_PHYSICS_STEPS

    if isinstance(scenario, Scenario):
        scn = load_from_model(scenario, settings) if settings else scenario
    else:
        scn = load(scenario, **settings)
    most = max_physics_steps or MAX_PHYSICS_STEPS
    return Run(scn, run_scenario(scn, progress=progress, max_physics_steps=most, keep_partial=keep_partial))


def load_from_model(scenario: Scenario, settings: dict) -> Scenario:
    """A scenario model with ``settings`` applied (validated again)."""
    from twin.scenario import scenario_from_dict
    from twin.settings import set_fields

    return scenario_from_dict(set_fields(scenario.model_dump(exclude_unset=True), _paths(settings)))


def _refuse_all_failed(table) -> None:
    """Refuse a sweep whose every sample was an ``error`` row (bad input for all of them), with
    the first sample's error: a summary of nothing would exit 0.

    Raises
    ------
    TwinInputError
        Every row of ``table`` (the sweep's rows, sorted by index) has the status ``error``.
    """
    statuses = table.column("status").to_pylist()
    if statuses and all(s == "error" for s in statuses):
        first = table.slice(0, 1).to_pylist()[0]
        raise TwinInputError(
            "sweep",
            f"{len(statuses)} samples",
            f"every sample failed; the first (sample {first['index']}): {first['error']}",
        )


def sweep(
    target: str | Path,
    vary: list[str] | tuple = (),
    *,
    samples: int | None = None,
    seed: int | None = None,
    lhs: bool | None = None,
    out: str | Path | None = None,
    workers: int | None = None,
    scheduler: str | None = None,
    batch: int | None = None,
    resume: bool = False,
    progress: bool = False,
    **settings,
) -> Sweep:
    """Run a scenario (or a sweep TOML file) over sampled parameters on Dask, as ``twin sweep``.

    ``vary`` holds ``PATH=SPEC`` strings (``overrides.m=box``, ``disturbances.0.spindle_rpm=
    uniform(1000,3000)``...); ``settings`` change the scenario first, as for :func:`run`.  The
    defaults are the sweep file's, else 100 samples, seed 0, a local cluster of one worker per
    core, ``<scenario>_sweep.parquet``.

    Raises
    ------
    TwinInputError
        A bad variation, setting or option; or every sample failed (the first one's error; the
        rows stay in ``out``).
    """
    from twin.settings import parse_settings
    from twin.sweeps import prepare_sweep, sweep_spec
    from twin.sweeps.run import check_batch_size, make_client, read_sweep, run_sweep
    from twin.sweeps.summary import certificates, summarize

    spec = sweep_spec(str(target))
    variations = [f"{k}={v}" for k, v in spec.vary.items()] + list(vary)
    if workers is not None and not 1 <= workers <= 256:
        raise TwinInputError("workers", workers, "must be from 1 to 256")
    if workers is not None and scheduler:
        raise TwinInputError("workers", workers, "give workers or scheduler, not both")
    sets = {**parse_settings(spec.set), **_paths(settings)}
    sw = prepare_sweep(
        spec.scenario,
        settings=sets,
        vary=variations,
        samples=spec.samples if samples is None else samples,
        seed=spec.seed if seed is None else seed,
        latin_hypercube=spec.latin_hypercube if lhs is None else lhs,
    )
    out = Path(out or spec.out or f"{sw.name}_sweep.parquet")
    if not out.parent.is_dir():
        raise TwinInputError("out", str(out), f"folder {str(out.parent)!r} does not exist")
    batch_size = spec.batch_size if batch is None else batch
    check_batch_size(batch_size)  # before a cluster starts
    client = make_client(workers, scheduler)
    try:
        done = run_sweep(
            sw.scenario,
            sw.plan,
            axes=sw.axes,
            out=out,
            client=client,
            batch_size=batch_size,
            resume=resume,
            progress=progress,
        )
    finally:
        client.close()
    table = read_sweep(out)
    _refuse_all_failed(table)
    summary = summarize(table, sw.plan, sw.axes)
    summary.update(
        scenario=sw.name,
        out=str(out),
        wall_s=done.wall_s,
        ran=done.ran,
        skipped=done.skipped,
        certificates=certificates(sw.machine, sw.controller, sw.plan),
    )
    return Sweep(summary, out, table, sw.plan, sw.axes, done.interrupted)


def fidelity(machines: list[str] | tuple = (), **symbols: float) -> Fidelity:
    """Each machine's (or fidelity case's) twin against its transfer function, as
    ``twin fidelity``: time NRMSE, FRF errors, gear slip and ``pass`` per case; ``symbols``
    override machine parameters by their source symbols (``m=60.0``).

    Raises
    ------
    TwinInputError
        An unknown machine or case, or an override the machine refuses, before anything runs.
    """
    from twin.fidelity import CASES, case_machine
    from twin.fidelity import fidelity as check
    from twin.machines import get_machine

    names = list(machines) or list(CASES)
    for name in names:  # validate everything before computing anything
        get_machine(case_machine(name)[0]).resolve(symbols)
    return Fidelity([check(name, symbols) for name in names])


def reproduce(
    paper: str,
    *,
    samples: int = DEFAULT_SAMPLES,
    twin_samples: int = DEFAULT_TWIN_SAMPLES,
    random_seed: int = DEFAULT_SEED,
    progress: bool = False,
) -> dict:
    """A paper's reproduction, as ``twin reproduce PAPER --json`` returns it (``yadav2020`` ...
    ``choi1999``); ``twin_samples = 0`` leaves the twin out.

    Raises
    ------
    TwinInputError
        An unknown paper, or sample counts out of range.
    """
    from twin.reproductions.registry import REPRODUCTIONS, reproduction

    if paper not in REPRODUCTIONS:
        raise TwinInputError("source", paper, f"no reproduction of that paper yet (known: {', '.join(REPRODUCTIONS)})")
    if samples < 1 or twin_samples < 0:
        raise TwinInputError(
            "samples" if samples < 1 else "twin_samples",
            samples if samples < 1 else twin_samples,
            "must be >= 1 (samples) / >= 0 (twin_samples)",
        )
    return reproduction(paper).run(samples, twin_samples, random_seed, progress)


def program(file: str | Path, machine: str | None = None, **settings: Any) -> Program:
    """A part program as ``twin gcode FILE`` reads it, and with a ``machine`` plans it (cycle time,
    feed-only time, limits and largest values per axis, path deviation).

    Settings are keyword arguments with dotted paths below ``planner``, ``reference`` and
    ``drive`` (``planner__tolerance_mm=0.02``, ``**{"planner.feed_override": 0.8}``,
    ``drive__saturation_V=10``: the drives are checked against it).

    Raises
    ------
    TwinInputError
        The program's first bad line (``file:line``, its text and the reason), or a bad setting.
    """
    from twin.errors import input_file
    from twin.gcode.reader import read_program
    from twin.references.gcode import planned_for, program_settings

    reference, planner, saturation_V = program_settings(str(file), _paths(settings))
    input_file(file, "file")
    moves = list(read_program(file, reference.reader_settings()))  # a bad line: GcodeError, a TwinInputError
    planned = None if machine is None else planned_for(file, moves, machine, planner, saturation_V)
    return Program(str(file), moves, planned)


def frf(machine: str, overrides: dict[str, float] | None = None, **settings: Any) -> Frf:
    """An axis's FRF measured on the twin, as ``twin frf``; ``settings`` are
    :class:`twin.commissioning.frf.FrfSettings`'s fields (``axis="y"``, ``loop="open"``,
    ``sensor="motor"``, ``excitation="chirp"``, ``amplitude_V``, ...); on a machine file with
    ``screw_root_diameter_m``, ``overrides={"x_nut_position_m": 0.1}`` puts the nut there.

    Raises
    ------
    TwinInputError
        An unknown setting, or a bad value of one (named).
    """
    from twin.commissioning.frf import FrfSettings, measure, nut_stiffness

    try:
        chosen = FrfSettings(**settings)
    except TypeError:
        raise TwinInputError(
            "settings", sorted(settings), f"known: {', '.join(FrfSettings.__dataclass_fields__)}"
        ) from None
    return Frf(measure(machine, chosen, overrides), nut_stiffness(machine, chosen.axis, overrides))


def lobes(
    scenario,
    *,
    method: str = "both",
    rpm: tuple[float, float, int] | None = None,
    depth_max_mm: float | None = None,
    immersion: float | None = None,
    mode: str | None = None,
    tool_number: int | None = None,
    feed_per_tooth_mm: float = 0.1,
    **settings: Any,
) -> StabilityLobes:
    """The stability lobes of a scenario's tool (a name, a path or a :func:`load`-ed scenario,
    with ``settings``), as ``twin lobes``: ``method`` "zoa", "sd" or "both"; ``rpm`` (low,
    high, count); the cut's ``immersion`` (``a_e/D``) and ``mode`` ("up"/"down"); see
    :class:`twin.commissioning.lobes.LobesSettings`.  With a stock and a program, each cutting
    line's chatter check in ``summary["lines"]``.

    Raises
    ------
    TwinInputError
        A bad setting, no tool with ``dynamics``, semi-discretization of a measured FRF.
    """
    from twin.commissioning.lobes import LobesSettings
    from twin.commissioning.lobes import lobes as compute

    scn = load_from_model(scenario, settings) if not isinstance(scenario, str | Path) else load(scenario, **settings)
    chosen = LobesSettings(method, rpm, depth_max_mm, immersion, mode, tool_number, feed_per_tooth_mm)
    return StabilityLobes(scn.name, compute(scn, chosen))


def calibrate(
    machine: str,
    trace: str | Path,
    fit: list[str],
    *,
    overrides: dict[str, float] | None = None,
    axis: str = "x",
    sensor: str = "table",
    progress: bool = False,
    timestep_s: float | None = None,
) -> Calibration:
    """Fit machine parameters to a measured trace or FRF, as ``twin calibrate`` (``axis`` and
    ``sensor``: where an FRF was measured; ``progress``: a progress bar; ``timestep_s``: the
    physics step of the fit's twin runs, default the machine's)."""
    from twin.commissioning.calibration import CalibrationProblem, solve

    problem = CalibrationProblem.from_inputs(
        machine, trace, list(fit), overrides=overrides, axis=axis, sensor=sensor, timestep_s=timestep_s
    )
    return Calibration(solve(problem, progress=progress))


def tune(
    machine: str,
    overrides: dict[str, float] | None = None,
    control_period_s: float | None = None,
    feedback: str | None = None,
) -> Tuning:
    """Each axis's tuned cascade with its margins and bandwidth, as ``twin tune --no-verify``
    (``feedback``: :data:`twin.sim.drive.FEEDBACK`, default the machine's);
    :meth:`twin.results.Tuning.verify` runs it on the twin."""
    from twin.commissioning.tuning import tune as design
    from twin.machines import is_machine_file

    where = str(Path(machine).resolve()) if is_machine_file(machine) else machine
    return Tuning(where, design(machine, overrides, control_period_s, feedback))
