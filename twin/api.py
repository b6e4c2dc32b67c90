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

from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from twin.errors import TwinInputError
from twin.reproductions import DEFAULT_SAMPLES, DEFAULT_SEED, DEFAULT_TWIN_SAMPLES

if TYPE_CHECKING:  # the heavy modules load on first use, not with `import twin`
    import pandas as pd
    import pyarrow as pa

    from twin.sampling import Plan
    from twin.scenario import Scenario
    from twin.sim.runner import RunResult


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


@dataclass
class Run:
    """One closed-loop run.

    Attributes
    ----------
    scenario : twin.scenario.Scenario
    result : twin.sim.runner.RunResult
        The raw arrays (SI units) at the recorded ticks, and metrics over every tick.
    status : str
        ``ok``, or ``diverged`` / ``interrupted`` for a run that stopped early (see
        :func:`run`'s ``keep_partial``).
    """

    scenario: Scenario
    result: RunResult
    status: str = "ok"
    extra: dict = field(default_factory=dict)

    @property
    def summary(self) -> dict:
        """What ``twin run --json`` prints: scenario, machine, status, completed ticks, max and
        RMS tracking error per axis (µm), the largest cutting force (N), the contour error for
        2-D paths (µm) and the loop that ran."""
        from twin.metrics import tracking_summary

        done = self.result.info["completed_ticks"]
        return {
            "scenario": self.scenario.name,
            "machine": self.scenario.machine,
            "status": self.status,
            **self.extra,
            "completed_ticks": done,
            **(tracking_summary(self.result) if done else {}),
            "loop": self.result.info["loop"],
        }

    def lines_to_parquet(self, path: str | Path) -> Path:
        """Write the per-line table of a G-code run (``summary["lines"]``, the per-axis
        tracking errors as columns ``max_tracking_error_um_<axis>``) to a Parquet file.

        Raises
        ------
        TwinInputError
            The run has no G-code reference.
        """
        import pyarrow as pa
        import pyarrow.parquet as pq

        rows = self.summary.get("lines")
        if not rows:
            raise TwinInputError("lines", str(path), "the run has no G-code reference: no per-line table")
        flat = []
        for row in rows:
            per_axis = {f"max_tracking_error_um_{a}": v for a, v in row["max_tracking_error_um"].items()}
            flat.append({**{k: v for k, v in row.items() if k != "max_tracking_error_um"}, **per_axis})
        pq.write_table(pa.Table.from_pylist(flat), Path(path))
        return Path(path)

    def to_pandas(self) -> pd.DataFrame:
        """The run's named series as a ``pandas.DataFrame`` indexed by simulated time (s), one
        column per series of the recording, named ``<path> (<unit>)``: ``reference/x (mm)``,
        ``actual/x (mm)``, ``error/x (µm)``, ``control/x (V)``, ``force/drive/x (N)`` or
        ``torque/drive/x (N m)``, ``force/cutting/x (N)``, ``joints/x/motor/angle (rad)``..."""
        import pandas as pd

        from twin.series import named_series

        columns = {f"{s.path} ({s.unit})": s.values for s in named_series(self.result)}
        return pd.DataFrame(columns, index=pd.Index(self.result.t_s, name="time (s)"))

    def record(self, path: str | Path) -> Path:
        """Write the Rerun recording (``.rrd``) of the run and return its path."""
        from twin.recording import record

        path = Path(path)
        record(self.result, path)
        return path

    def write_part(self, folder: str | Path) -> list[Path]:
        """Write the virtual part of a run with a stock into ``folder`` (created if missing):
        ``<scenario>_part.stl``, the actual part's closed mesh (mm), and
        ``<scenario>_part_map.parquet``, the nominal and actual height maps and their
        difference by cell (:mod:`twin.process.part_map`); their paths.

        Raises
        ------
        TwinInputError
            The run has no virtual part (no stock, or it stopped early).
        """
        part = self.result.part
        if part is None or part.maps is None:
            raise TwinInputError("part", str(folder), "the run has no virtual part: give [stock] and run to the end")
        folder = Path(folder)
        folder.mkdir(parents=True, exist_ok=True)
        name = self.scenario.name
        return [
            part.maps.to_stl(folder / f"{name}_part.stl"),
            part.maps.to_parquet(folder / f"{name}_part_map.parquet"),
        ]

    def plots(self, folder: str | Path) -> list[Path]:
        """Write the PNG plots of ``twin run --plots`` into ``folder``; their paths."""
        from twin.plots import write_plots

        return write_plots(self.result, Path(folder), self.scenario.name)


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
        On divergence or Ctrl-C, return the partial :class:`Run` (``status`` says which)
        instead of raising.

    Raises
    ------
    TwinInputError
        Bad input, before anything runs.
    SimulationDiverged, RunInterrupted
        Unless ``keep_partial``.
    """
    from twin.errors import RunInterrupted, SimulationDiverged
    from twin.scenario import Scenario, run_scenario
    from twin.sim.runner import MAX_PHYSICS_STEPS

    if isinstance(scenario, Scenario):
        scn = load_from_model(scenario, settings) if settings else scenario
    else:
        scn = load(scenario, **settings)
    try:
        result = run_scenario(scn, progress=progress, max_physics_steps=max_physics_steps or MAX_PHYSICS_STEPS)
    except (SimulationDiverged, RunInterrupted) as exc:
        if not keep_partial or exc.result is None:
            raise
        status = "diverged" if isinstance(exc, SimulationDiverged) else "interrupted"
        return Run(scn, exc.result, status, {"sim_time_s": exc.sim_time_s})
    return Run(scn, result)


def load_from_model(scenario: Scenario, settings: dict) -> Scenario:
    """A scenario model with ``settings`` applied (validated again)."""
    from twin.scenario import scenario_from_dict
    from twin.settings import set_fields

    return scenario_from_dict(set_fields(scenario.model_dump(exclude_unset=True), _paths(settings)))


@dataclass
class Sweep:
    """A finished (or interrupted) sweep.

    Attributes
    ----------
    summary : dict
        What ``twin sweep --json`` prints: bands, the worst case, certificates, counts.
    out : Path
        The Parquet dataset folder, one row per sample.
    table : pyarrow.Table
        Its rows, as read back.
    plan : twin.sampling.Plan
        The samples' plan.
    axes : tuple of str
        The machine's axes.
    interrupted : bool
        Whether Ctrl-C stopped it (``resume=True`` with the same ``out`` completes it).
    """

    summary: dict
    out: Path
    table: pa.Table
    plan: Plan
    axes: tuple[str, ...]
    interrupted: bool = False

    def to_pandas(self) -> pd.DataFrame:
        """Every sample's row (its parameters, status and metrics) as a ``pandas.DataFrame``."""
        return self.table.to_pandas()

    def plots(self, folder: str | Path) -> list[Path]:
        """Write the PNGs of ``twin sweep --plots`` into ``folder``; their paths."""
        from twin.sweeps.summary import write_sweep_plots

        return write_sweep_plots(self.table, self.plan, self.axes, Path(folder))


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
    """
    from twin.settings import parse_settings
    from twin.sweeps import prepare_sweep, sweep_spec
    from twin.sweeps.run import make_client, read_sweep, run_sweep
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
        sets,
        variations,
        spec.samples if samples is None else samples,
        spec.seed if seed is None else seed,
        spec.latin_hypercube if lhs is None else lhs,
    )
    out = Path(out or spec.out or f"{sw.name}_sweep.parquet")
    if not out.parent.is_dir():
        raise TwinInputError("out", str(out), f"folder {str(out.parent)!r} does not exist")
    client = make_client(workers, scheduler)
    try:
        done = run_sweep(
            sw.scenario,
            sw.plan,
            sw.axes,
            out,
            client,
            spec.batch_size if batch is None else batch,
            resume,
            progress=progress,
        )
    finally:
        client.close()
    table = read_sweep(out)
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


def fidelity(machines: list[str] | tuple = (), **symbols: float) -> list[dict]:
    """Each machine's (or fidelity case's) twin against its transfer function, as
    ``twin fidelity --json``: time NRMSE, FRF errors, gear slip and ``pass``; ``symbols``
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
    return [check(name, symbols) for name in names]


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


def program(file: str | Path, machine: str | None = None, **settings: Any) -> dict:
    """A part program as ``twin gcode FILE --json`` reports it: ``moves`` as read (line, kind,
    end_mm, arcs' plane, center_mm and turns, feed, spindle) and, with a ``machine``,
    ``planned`` (cycle time, feed-only time, limits and largest values per axis, path deviation).

    Settings are keyword arguments with dotted paths below ``planner`` and ``reference``
    (``planner__tolerance_mm=0.02`` or ``**{"planner.feed_override": 0.8}``).

    Raises
    ------
    TwinInputError
        The program's first bad line (``file:line``, its text and the reason), or a bad setting.
    """
    from twin.errors import input_file
    from twin.gcode.planner import PlanningError, plan
    from twin.gcode.reader import read_program
    from twin.gcode.report import planned_summary
    from twin.machines import build
    from twin.references.gcode import program_settings

    reference, planner = program_settings(str(file), _paths(settings))
    input_file(file, "file")
    moves = list(read_program(file, reference.reader_settings()))  # a bad line: GcodeError, a TwinInputError
    out: dict[str, Any] = {"file": str(file), "moves": [m.as_dict() for m in moves]}
    if machine is not None:
        limits = planner.limits(build(machine).motion_limits)
        try:
            out["planned"] = planned_summary(plan(moves, limits, planner), limits)
        except PlanningError as exc:
            raise TwinInputError("file", str(file), str(exc)) from None
    return out


def frf(machine: str, overrides: dict[str, float] | None = None, **settings: Any) -> dict:
    """An axis's FRF measured on the twin, as ``twin frf --json`` (plus ``run``, the
    simulation); ``settings`` are :class:`twin.commissioning.frf.FrfSettings`'s fields (``axis="y"``,
    ``loop="open"``, ``sensor="motor"``, ``excitation="chirp"``, ``amplitude_V``, ...)."""
    from twin.commissioning.frf import FrfSettings, measure

    try:
        chosen = FrfSettings(**settings)
    except TypeError:
        raise TwinInputError(
            "settings", sorted(settings), f"known: {', '.join(FrfSettings.__dataclass_fields__)}"
        ) from None
    return measure(machine, chosen, overrides)


def calibrate(
    machine: str, trace: str | Path, fit: list[str], overrides: dict[str, float] | None = None, axis: str = "x"
) -> dict:
    """Fit machine parameters to a measured trace or FRF, as ``twin calibrate --json``."""
    from twin.commissioning.calibration import calibrate as fit_machine

    return fit_machine(machine, trace, list(fit), overrides, axis)


def tune(
    machine: str,
    overrides: dict[str, float] | None = None,
    control_period_s: float | None = None,
    feedback: str | None = None,
) -> dict:
    """Each axis's tuned cascade with its margins and bandwidth, as ``twin tune --json
    --no-verify`` (``feedback``: :data:`twin.sim.drive.FEEDBACK`, default the machine's);
    :func:`twin.commissioning.tuning.verify` runs it on the twin."""
    from twin.commissioning.tuning import tune as design

    return design(machine, overrides, control_period_s, feedback)
