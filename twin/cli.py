"""Command line: ``twin run | demo | gcode | fidelity | frf | lobes | calibrate | tune | mjcf | reproduce | sweep``,
``twin list | bench``.

Bad input (unknown machine, controller or field, invalid values, malformed TOML) prints one
line ``error: <field> = <value>: <reason>`` on stderr and exits with code 2; a diverging
simulation prints the simulated time and exits with code 3.
"""

from __future__ import annotations

import os
import signal
import sys
from collections.abc import Sequence
from functools import wraps
from pathlib import Path

import typer

from twin import exits
from twin.errors import TwinInputError
from twin.records import Inspected, LineRow, LineWarning, RunRecords, plan_warning
from twin.reproductions import DEFAULT_SAMPLES, DEFAULT_SEED, DEFAULT_TWIN_SAMPLES

app = typer.Typer(
    add_completion=False,
    pretty_exceptions_enable=False,
    no_args_is_help=True,
    help="Digital twin of CNC XY feed drives (MuJoCo).",
)


def _guard(func):
    """Run a command under the contract of :mod:`twin.exits`: the twin's own errors become one
    stderr line and their exit code, warnings become errors, and anything unexpected one
    ``internal error`` line with exit code 70 (never a traceback, never exit code 1)."""

    @wraps(func)
    def wrapper(*args, **kwargs):
        try:
            with exits.warnings_as_errors():
                return func(*args, **kwargs)
        except (typer.Exit, BrokenPipeError):
            raise
        except (Exception, KeyboardInterrupt) as exc:
            raise typer.Exit(exits.report(exc)) from None

    return wrapper


def _echo_json(value, indent: int = 1) -> None:
    """Print ``value`` as one strict JSON document (:func:`twin.exits.strict_json`)."""
    typer.echo(exits.strict_json(value, indent, default=float))


def _check_output(option: str, path: Path | None, suffix: str | None = None) -> None:
    """Refuse an output path before any work: wrong suffix, or a folder that does not exist."""
    if path is None:
        return
    if suffix and path.suffix != suffix:
        raise TwinInputError(option, str(path), f"the file must end in {suffix}")
    if not os.path.isdir(path.parent):
        raise TwinInputError(option, str(path), f"folder {str(path.parent)!r} does not exist")
    if os.path.isdir(path):
        raise TwinInputError(option, str(path), "is a folder")
    limit = os.pathconf(path.parent, "PC_NAME_MAX")
    if len(os.fsencode(path.name)) > limit:
        raise TwinInputError(option, str(path), f"the file's name is over the system's {limit} bytes")


def _check_folder(plots: Path | None, option: str = "--plots") -> None:
    """Refuse a ``--plots`` (or ``option``) path that exists and is not a folder (a missing one
    is created)."""
    if plots is not None and os.path.exists(plots) and not os.path.isdir(plots):
        raise TwinInputError(option, str(plots), "exists and is not a folder")


def _print_worst_lines(rows: Sequence[LineRow]) -> None:
    """The program's worst lines (contour error, else tracking error) with their text."""
    if not rows:
        return
    contour = rows[0].max_contour_error_um is not None
    typer.echo(f"  worst lines ({'max contour' if contour else 'max tracking'} error, um):")
    for row in sorted(rows, key=lambda row: row.worst_error_um, reverse=True)[:WORST_LINES]:
        span = f"{row.t_start_s:.3f}-{row.t_end_s:.3f} s"
        typer.echo(f"    {row.line:>6}  {row.worst_error_um:>9.3f}  {span}  {row.text}")


#: Warnings of each kind the text summary prints (all are in --json).
SHOWN_WARNINGS = 20


def _warning_line(warning: LineWarning) -> str:
    """A warning as the text summary prints it: its line (or the run), message and the line's text."""
    where = "   run" if warning.line is None else f"line {warning.line:>6}"
    return f"{where}  {warning.message}  {warning.text}"


def _print_warnings(title: str, warnings: Sequence[LineWarning], total: int, indent: str = "  ") -> None:
    """A run's or a program's warnings of one kind under ``title``, a line each, the first
    :data:`SHOWN_WARNINGS`; ``total`` counts them all (listed or not)."""
    if not warnings:
        return
    typer.echo(f"{indent}{title} ({total}):")
    for warning in warnings[:SHOWN_WARNINGS]:
        typer.echo(f"{indent}  {_warning_line(warning)}")
    if total > SHOWN_WARNINGS:
        listed = "them all" if total == len(warnings) else str(len(warnings))
        typer.echo(f"{indent}  ... {total - SHOWN_WARNINGS} more (--json lists {listed})")


def _fail_on_warnings(title: str, warnings: Sequence[LineWarning], total: int) -> None:
    """Under ``--strict``: the first of ``warnings`` as the error line, exit 4."""
    if warnings:
        first = warnings[0]
        where = "the run" if first.line is None else f"line {first.line}"
        typer.echo(f"error: {total} {title} under --strict; the first: {where}: {first.message}", err=True)
        raise typer.Exit(exits.CHECK_FAILED)


def _print_chatter(records: RunRecords) -> None:
    """The run's chatter indicator and frequency, then the chatter warnings, a line each: by
    program line, or the run's."""
    if records.chatter is None:
        return
    typer.echo(f"  {records.chatter.report_line()}")
    warnings = records.chatter_warnings
    _print_warnings("chatter warnings", warnings, len(warnings))


def _print_chatter_check(rows: Sequence[LineRow]) -> None:
    """The program's cutting lines over their critical depth (the tool's lobes), worst first."""
    checked = [row.stability for row in rows if row.stability is not None]
    if not checked:
        return
    over = sorted(
        (check for check in checked if (check["margin"] or float("inf")) < 1),
        key=lambda check: check["margin"],
    )
    typer.echo(
        f"  chatter check (zero-order lobes): {len(checked)} cutting line(s), {len(over)} over their critical depth"
    )
    for check in over[:WORST_LINES]:
        typer.echo(f"    {check['text']}")


def _print_part(summary: dict, inspection: Sequence[Inspected]) -> None:
    """The virtual part's wall error and each inspected feature, a line each."""
    part = summary.get("part")
    if part is None:
        return
    stats = part["surface_error_um"]
    if stats:
        typer.echo(
            f"  virtual part: wall error {stats['min']:+.3f} to {stats['max']:+.3f} µm, RMS {stats['rms']:.3f} µm"
            f" ({part['wall_points']} points at Z {', '.join(f'{z:g}' for z in part['wall_levels_mm'])} mm)"
        )
    floors = part.get("floor_error_um")
    if floors:
        typer.echo(
            f"  floors and surfaces: error {floors['min']:+.3f} to {floors['max']:+.3f} µm, RMS {floors['rms']:.3f} µm"
            f" ({floors['cells']} cells)"
        )
    if part.get("skipped_levels_mm"):
        typer.echo(
            f"  walls not read at Z {', '.join(f'{z:g}' for z in part['skipped_levels_mm'])} mm: {part['skipped_note']}"
        )
    for feature in inspection:
        typer.echo(f"    {feature.report_line()}")


def _print_summary(name: str, summary: dict) -> None:
    typer.echo(f"{name}")
    for key, value in summary.items():
        if isinstance(value, dict):
            value = "  ".join(f"{a}: {v:.3f}" for a, v in value.items())
        elif isinstance(value, float):
            value = f"{value:.3f}"
        typer.echo(f"  {key:<28} {value}")


def _run(
    scenario: str,
    rrd: Path | None,
    as_json: bool,
    settings: list[str] | None = None,
    max_steps: int | None = None,
    plots: Path | None = None,
    lines: Path | None = None,
    strict: bool = False,
    part: Path | None = None,
) -> None:
    """Run a scenario and report it; a run that diverges or is interrupted still reports,
    records and plots what it computed before the error line.  With ``strict``, machining
    warnings and warnings against the machine (travel, drives) end it with exit code 4 (after
    the report)."""
    from twin import api
    from twin.scenario import load_scenario
    from twin.settings import parse_settings

    _check_output("--rrd", rrd, ".rrd")
    _check_output("--lines", lines, ".parquet")
    _check_folder(plots)
    _check_folder(part, "--part")
    scn = load_scenario(scenario, parse_settings(settings or []), "--set ")
    if part is not None and scn.stock is None:
        raise TwinInputError("--part", str(part), "the virtual part is cut from a stock: the scenario has no [stock]")
    if lines is not None and scn.reference.type != "gcode":
        kind = scn.reference.type
        raise TwinInputError("--lines", str(lines), f"a per-line table needs a G-code reference, not {kind}")
    if rrd is not None and scn.record_every_ticks == 0:
        raise TwinInputError("record_every_ticks", 0, "the run keeps metrics only: nothing to write to --rrd")
    done = api.run(scn, progress=False if as_json else None, max_physics_steps=max_steps, keep_partial=True)
    _report(done, rrd, as_json, plots, lines, part)  # a run that stopped early too: what it computed
    if done.stopped is not None:
        raise done.stopped
    if strict:
        records = done.records  # what the report printed, not computed again
        _fail_on_warnings("machining warning(s)", records.machining_warnings, records.machining_warnings_total)
        _fail_on_warnings("warning(s) against the machine", records.plan_warnings, records.plan_warnings_total)
        chatter = records.chatter_warnings
        _fail_on_warnings("chatter warning(s)", chatter, len(chatter))


#: Lines of a program the text summary names, worst first.
WORST_LINES = 5


def _report(
    done, rrd: Path | None, as_json: bool, plots: Path | None, lines: Path | None = None, part: Path | None = None
) -> None:
    """Print the run's summary (text or JSON), write its recording, its plots and, for a
    program, its per-line table and (with a stock) its virtual part's files."""
    summary = done.summary
    if as_json:
        _echo_json(summary, 2)
    else:
        _print_summary(
            f"{done.scenario.name}: {done.scenario.description}",
            {
                k: v
                for k, v in summary.items()
                if k
                not in (
                    "scenario",
                    "machine",
                    "lines",
                    "machining_warnings",
                    "part",
                    "inspection",
                    "plan_warnings",
                    "plan_warnings_total",
                    "chatter",
                    "chatter_warnings",
                )
            },
        )
        records = done.records
        _print_worst_lines(records.lines)
        _print_chatter_check(records.lines)
        _print_warnings("machining warnings", records.machining_warnings, records.machining_warnings_total)
        _print_warnings("warnings against the machine", records.plan_warnings, records.plan_warnings_total)
        _print_chatter(records)
        _print_part(summary, records.inspection)
    if lines is not None:
        done.lines_to_parquet(lines)
        typer.echo(f"per-line table written to {lines}", err=as_json)
    if rrd is not None and len(done.result.t_s):
        done.record(rrd)  # rerun is imported only when a recording is asked for
        typer.echo(f"recording written to {rrd} (view with: rerun {rrd})", err=as_json)
    if plots is not None and len(done.result.t_s):
        for path in done.plots(plots):  # matplotlib is imported only when plots are asked for
            typer.echo(f"plot written to {path}", err=as_json)
    if part is not None and done.result.part is not None:
        for path in done.write_part(part):
            typer.echo(f"part written to {path}", err=as_json)


@app.command()
@_guard
def run(
    scenario: str = typer.Argument(..., help="Scenario TOML file, or a bundled scenario name"),
    rrd: Path = typer.Option(None, "--rrd", help="Write a Rerun recording to this .rrd file"),
    as_json: bool = typer.Option(False, "--json", help="Print metrics as JSON"),
    sets: list[str] = typer.Option(
        None, "--set", help="Change a field: PATH=VALUE, e.g. disturbances.0.spindle_rpm=2500"
    ),
    max_steps: int = typer.Option(
        None,
        "--max-steps",
        min=1,
        help="Physics steps a run may take (default 20 000 000: 3-7 minutes of a plain run on 2 cores)",
    ),
    plots: Path = typer.Option(
        None, "--plots", help="Write PNG plots (errors, inputs, forces, contour) to this folder"
    ),
    lines: Path = typer.Option(None, "--lines", help="A G-code run: write its per-line table to this .parquet"),
    strict: bool = typer.Option(
        False,
        "--strict",
        help="Exit with code 4 if the program crashes or misuses the tool (machining warnings), leaves the "
        "machine's travel, asks more than its drives deliver or the cut chatters",
    ),
    part: Path = typer.Option(
        None,
        "--part",
        help="A run with a stock: write its virtual part to this folder (mesh .stl, height maps .parquet)",
    ),
):
    """Run a closed-loop scenario and print its tracking metrics (a G-code run: per program line too)."""
    _run(scenario, rrd, as_json, sets, max_steps, plots, lines, strict, part)


@app.command()
@_guard
def demo(
    rrd: Path = typer.Option(Path("demo.rrd"), "--rrd", help="Rerun recording to write"),
    as_json: bool = typer.Option(False, "--json", help="Print metrics as JSON"),
    plots: Path = typer.Option(None, "--plots", help="Write PNG plots to this folder"),
):
    """The main job: Choi 1999's cutting circle (R 28 mm, 4800 mm/min, 10000 rpm end milling) on the
    linear-motor table under the MIMO H-infinity loop-shaping controller with ZPETC."""
    _run("choi1999_mimo_cutting", rrd, as_json, plots=plots)


def _gain_margin(loop: dict) -> str:
    """A loop's gain margin for the text report: dB at its phase crossover, or infinite."""
    if loop["gain_margin_db"] is None:
        return "infinite"
    return f"{loop['gain_margin_db']:.1f} dB at {loop['gain_margin_hz']:.0f} Hz"


def _parse_sets(sets: list[str]) -> dict[str, float]:
    out = {}
    for item in sets:
        key, sep, value = item.partition("=")
        if not sep or not key:
            raise TwinInputError("--set", item, "use SYMBOL=VALUE")
        try:
            out[key.strip()] = float(value)
        except ValueError:
            raise TwinInputError(f"--set {key}", value, "must be a number") from None
    return out


def _timestep_and_sets(sets: list[str], option: str = "--set timestep_s") -> tuple[float | None, dict[str, float]]:
    """``--set`` items as the physics step (``timestep_s=S``, None where not given, within the
    scenario's bounds) and the parameter overrides (the others)."""
    from twin.scenario import MAX_TIMESTEP_S, MIN_TIMESTEP_S

    overrides = _parse_sets(sets)
    timestep = overrides.pop("timestep_s", None)
    if timestep is not None and not (MIN_TIMESTEP_S <= timestep <= MAX_TIMESTEP_S):
        raise TwinInputError(option, timestep, f"must be in [{MIN_TIMESTEP_S:g}, {MAX_TIMESTEP_S:g}] s")
    return timestep, overrides


@app.command()
@_guard
def fidelity(
    machine: list[str] = typer.Option(
        None, "--machine", help="Machine(s), fidelity case(s) or machine file(s) (FILE.toml); default all"
    ),
    sets: list[str] = typer.Option(None, "--set", help="Parameter override SYMBOL=VALUE"),
    as_json: bool = typer.Option(False, "--json", help="Print the results as JSON"),
):
    """Compare each MJCF twin with its transfer function (time, frequency, gear slip).

    Cases: every machine, and linear_motor_xy+average_force (Choi 1999's cutting-force model
    against its coupled eq. (11) model).
    """
    from twin import api
    from twin.fidelity import TARGETS

    results = api.fidelity(machine or [], **_parse_sets(sets or []))
    if not as_json:
        for r in results.cases:
            typer.echo(
                f"{r['case']:<30} nrmse {r['time_nrmse']:.2e}  |dmag| {r['frf_max_mag_err_db']:.4f} dB  "
                f"|dphase| {r['frf_max_phase_err_deg']:.3f} deg  slip {r['coupling_slip_um']:.4f} um  "
                f"{'PASS' if r['pass'] else 'FAIL'}"
            )
    if as_json:
        _echo_json(results.summary, 2)
    else:
        typer.echo("targets: " + ", ".join(f"{k} <= {v}" for k, v in TARGETS.items()))
    failed = results.failed
    if failed:
        typer.echo(f"error: {len(failed)} case(s) miss their fidelity targets: {', '.join(failed)}", err=True)
        raise typer.Exit(exits.CHECK_FAILED)


@app.command()
@_guard
def reproduce(
    source: str = typer.Argument(..., help="Which paper, e.g. yadav2020 (twin list shows them)"),
    as_json: bool = typer.Option(False, "--json", help="Print everything as JSON"),
    rrd: Path = typer.Option(None, "--rrd", help="Record the nominal twin step runs to this .rrd"),
    plots: Path = typer.Option(None, "--plots", help="Write PNG step-response plots to this folder"),
    samples: int = typer.Option(DEFAULT_SAMPLES, "--samples", help="Monte Carlo samples on the transfer functions"),
    twin_samples: int = typer.Option(
        DEFAULT_TWIN_SAMPLES, "--twin-samples", help="Random box samples on the twin (besides the paper's 10)"
    ),
    seed: int = typer.Option(DEFAULT_SEED, "--seed", help="Seed of the random samples"),
):
    """Reproduce a paper's design procedures and tables (paper | transfer function | twin).

    Exits with code 4 if a twin number departs from its transfer-function number by more than 2 %.
    """
    from twin import api
    from twin.reproductions.registry import reproduction

    _check_output("--rrd", rrd, ".rrd")
    _check_folder(plots)
    res = api.reproduce(source, samples=samples, twin_samples=twin_samples, random_seed=seed, progress=not as_json)
    paper = reproduction(source)
    if as_json:
        _echo_json(res, 1)
    else:
        typer.echo(paper.format_report(res))
    if plots is not None:
        for path in paper.write_plots(plots, res):
            typer.echo(f"plot written to {path}", err=as_json)
    if rrd is not None:
        paper.record(rrd)
        typer.echo(f"recording written to {rrd} (view with: rerun {rrd})", err=as_json)
    if paper.failed(res):
        typer.echo(f"error: {source}: a twin number departs from its transfer function's by over 2 %", err=True)
        raise typer.Exit(exits.CHECK_FAILED)


@app.command()
@_guard
def sweep(
    target: str = typer.Argument(
        ..., help="Scenario (bundled name or TOML file), or a sweep TOML file (with a [vary] table)"
    ),
    vary: list[str] = typer.Option(
        None, "--vary", help="PATH=SPEC: box, corners, uniform(a,b), normal(mu,s), choice(v,...), grid(a,b,n), line(n)"
    ),
    sets: list[str] = typer.Option(None, "--set", help="Change a scenario field: PATH=VALUE"),
    samples: int = typer.Option(None, "--samples", help="Random draws (per grid/corner combination); default 100"),
    seed: int = typer.Option(None, "--seed", help="Sweep seed: every sample's draws and scenario seed"),
    lhs: bool = typer.Option(None, "--lhs/--no-lhs", help="Latin hypercube for the random specs"),
    out: Path = typer.Option(None, "--out", help="Parquet dataset folder (default <scenario>_sweep.parquet)"),
    workers: int = typer.Option(None, "--workers", help="Local cluster processes (default: one per core)"),
    scheduler: str = typer.Option(None, "--scheduler", help="Run on a Dask scheduler, e.g. tcp://host:8786"),
    batch: int = typer.Option(None, "--batch", help="Samples per Dask task (default 10)"),
    resume: bool = typer.Option(False, "--resume", help="Complete an interrupted sweep in --out"),
    plots: Path = typer.Option(None, "--plots", help="Write histogram and parameter PNGs to this folder"),
    as_json: bool = typer.Option(False, "--json", help="Print the summary as JSON"),
):
    """Run a scenario over sampled parameters on Dask: one Parquet row per sample, a summary of
    bands and the worst case, robustness certificates where one covers the box."""
    from twin import api
    from twin.settings import parse_settings
    from twin.sweeps.summary import format_summary

    _check_folder(plots)
    done = api.sweep(
        target,
        list(vary or []),
        samples=samples,
        seed=seed,
        lhs=lhs,
        out=out,
        workers=workers,
        scheduler=scheduler,
        batch=batch,
        resume=resume,
        progress=not as_json,
        **parse_settings(list(sets or [])),
    )
    summary = done.summary
    if as_json:
        _echo_json(summary, 1)
    else:
        typer.echo(format_summary(summary, summary["certificates"], done.axes))
        typer.echo(
            f"  {summary['ran']} samples run in {summary['wall_s']:.1f} s ({summary['skipped']} already in {done.out})"
        )
    if plots is not None:
        for path in done.plots(plots):
            typer.echo(f"plot written to {path}", err=as_json)
    if done.interrupted:
        typer.echo(
            f"error: sweep interrupted after {done.table.num_rows} of {len(done.plan)} samples; "
            f"twin sweep ... --out {done.out} --resume completes it",
            err=True,
        )
        raise typer.Exit(exits.INTERRUPTED)


@app.command()
@_guard
def gcode(
    file: Path = typer.Argument(..., help="The part program (RS-274/NGC, LinuxCNC's dialect)"),
    machine: str = typer.Option(None, "--machine", help="Plan the program for this machine (twin list)"),
    as_json: bool = typer.Option(False, "--json", help="Print the moves (and the plan) as JSON"),
    settings: list[str] = typer.Option(
        None,
        "--set",
        help="planner.KEY=VALUE, reference.KEY=VALUE or drive.saturation_V=VALUE, e.g. planner.tolerance_mm=0.02",
    ),
    strict: bool = typer.Option(
        False, "--strict", help="With --machine: exit with code 4 if the program leaves the travel or the drives' force"
    ),
):
    """Read a part program as LinuxCNC reads it and print its moves; with --machine, plan it
    (look-ahead, jerk-limited) and print the cycle time, the limits and the largest values.

    Nothing is printed on stdout for a program that is refused: the listing is written to a
    temporary file and copied out once the whole program has been read (and planned)."""
    from twin.gcode.listing import list_program
    from twin.gcode.reader import Settings

    reader_settings, planner, saturation_V = Settings(), None, None
    if settings or machine is not None:  # the settings' schema (pydantic) only where it is used
        from twin.references.gcode import planned_for, program_settings
        from twin.settings import parse_settings

        reference, planner, saturation_V = program_settings(str(file), parse_settings(settings or []))
        reader_settings = reference.reader_settings()
    plan = None if machine is None else (lambda moves: planned_for(file, moves, machine, planner, saturation_V))
    planned = list_program(file, reader_settings, as_json, plan)
    if planned is None:
        return
    warnings = [plan_warning(row) for row in planned["warnings"]]
    total = planned.get("warnings_total", len(warnings))
    if not as_json:
        typer.echo(f"planned for {machine}:")
        _print_summary(
            "",
            {
                k: v
                for k, v in planned.items()
                if k not in ("limits", "max", "violations", "notes", "warnings", "warnings_total")
            },
        )
        for over in planned["violations"]:
            typer.echo(f"  over a limit: line {over['line']}, {over['axis']} {over['quantity']} x{over['ratio']:.4f}")
        for note in planned["notes"]:
            typer.echo(f"  note: {note}")
        for axis in "xyz":
            lim, top = planned["limits"][axis], planned["max"][axis]
            typer.echo(
                f"  {axis}: v {top['velocity_m_per_s']:.4g}/{lim['velocity_m_per_s']:.4g} m/s, "
                f"a {top['acceleration_m_per_s2']:.4g}/{lim['acceleration_m_per_s2']:.4g} m/s^2, "
                f"j {top['jerk_m_per_s3']:.4g}/{lim['jerk_m_per_s3']:.4g} m/s^3 (largest/limit)"
            )
        _print_warnings("warnings against the machine", warnings, total)
    if strict:
        _fail_on_warnings("warning(s) against the machine", warnings, total)


@app.command()
@_guard
def frf(
    machine: str = typer.Argument(..., help="A machine (twin list) or a machine file (FILE.toml)"),
    axis: str = typer.Option("x", "--axis", help="The axis to excite"),
    loop: str = typer.Option("velocity", "--loop", help="open | velocity | position"),
    sensor: str = typer.Option("table", "--sensor", help="motor | table: whose position is measured"),
    feedback: str = typer.Option("motor", "--feedback", help="motor | table: the encoder the loop closes on"),
    excitation: str = typer.Option("prbs", "--excitation", help="prbs | chirp | multisine"),
    amplitude: float = typer.Option(1.0, "--amplitude", help="Excitation amplitude, V (peak)"),
    duration: float = typer.Option(16.0, "--duration", help="Recorded time, s"),
    f_max: float = typer.Option(1000.0, "--f-max", help="Highest frequency, Hz"),
    position: float = typer.Option(
        None, "--position", help="The nut's distance from the drive end, m (a machine file with screw_root_diameter_m)"
    ),
    sets: list[str] = typer.Option(None, "--set", help="Parameter override SYMBOL=VALUE"),
    as_json: bool = typer.Option(False, "--json", help="Print the FRF as JSON"),
    plots: Path = typer.Option(None, "--plots", help="Write the Bode plot (PNG) to this folder"),
    rrd: Path = typer.Option(None, "--rrd", help="Write the experiment as a Rerun recording (.rrd)"),
):
    """Measure an axis's frequency response on the twin as a commissioning tool does (excite,
    H1 with coherence, resonances and anti-resonances) beside the model's."""
    from twin import api
    from twin.commissioning.frf import MODE_MIN_COHERENCE, nut_stiffness

    _check_output("--rrd", rrd, ".rrd")
    _check_folder(plots)
    overrides = _parse_sets(sets or [])
    if position is not None:
        if nut_stiffness(machine, axis) is None:
            raise TwinInputError(
                "--position",
                position,
                f"needs screw_root_diameter_m on axis {axis} of a machine file (the stiffness it computes from the "
                "nut's position)",
            )
        overrides[f"{axis}_nut_position_m"] = position
    measured = api.frf(
        machine,
        overrides,
        axis=axis,
        loop=loop,
        sensor=sensor,
        excitation=excitation,
        amplitude_V=amplitude,
        duration_s=duration,
        f_max_hz=f_max,
        feedback=feedback,
    )
    if as_json:
        _echo_json(measured.summary, 1)
    else:
        m = measured.measurement
        typer.echo(
            f"{machine}: axis {axis}, {loop} loop on the {feedback} encoder, {sensor} sensor, "
            f"{excitation} {amplitude:g} V, "
            f"{len(m.frequency_hz)} lines {m.frequency_hz[0]:.2f}-{m.frequency_hz[-1]:.0f} Hz"
        )
        nut = measured.nut_stiffness
        if position is not None and nut is not None:
            typer.echo(
                f"  nut at {position:g} m: axial stiffness {nut['axial_N_per_m'] / 1e6:.4g} N/um, "
                f"torsion {nut['torsion_N_m_per_rad']:.4g} N m/rad"
            )
        doubtful = {(q.kind, q.frequency_hz) for q in m.modes if q.unreliable is not None}
        for label, kind, found, model in (
            ("resonances", "resonance", m.resonances_hz, m.model_resonances_hz),
            ("anti-resonances", "antiresonance", m.antiresonances_hz, m.model_antiresonances_hz),
        ):
            listed = ", ".join(f"{f:.1f}" + (" (unreliable)" if (kind, f) in doubtful else "") for f in found)
            modelled = ", ".join(f"{f:.1f}" for f in model)
            typer.echo(f"  {label} (Hz): {listed or 'none'}   model: {modelled or 'none'}")
        for q in m.modes:
            if q.unreliable is not None:
                kind = "anti-resonance" if q.kind == "antiresonance" else q.kind
                typer.echo(f"  unreliable {kind} {q.frequency_hz:.1f} Hz: {q.unreliable}")
        if m.incoherent_bands_hz:
            bands = ", ".join(f"{lo:.1f}" if lo == hi else f"{lo:.1f}-{hi:.1f}" for lo, hi in m.incoherent_bands_hz)
            typer.echo(f"  coherence < {MODE_MIN_COHERENCE:g} (a mode there is unreliable or missing) at {bands} Hz")
        error = m.max_model_error_db
        typer.echo(
            f"  coherence >= 0.9 on {100 * m.coherent_share:.0f} % of the lines; "
            f"largest |measured - model| there: {'-' if error is None else f'{error:.2f}'} dB"
        )
    if plots is not None:
        plots.mkdir(parents=True, exist_ok=True)
        path = measured.write_bode(plots / f"frf_{Path(machine).stem}_{axis}_{loop}_{sensor}.png")
        typer.echo(f"plot written to {path}", err=as_json)
    if rrd is not None:
        measured.record(rrd)
        typer.echo(f"recording written to {rrd} (view with: rerun {rrd})", err=as_json)


def _parse_rpm(text: str | None) -> tuple[float, float, int] | None:
    """``--rpm MIN:MAX:N`` as (low, high, count).

    Raises
    ------
    TwinInputError
        Not three fields, or not numbers.
    """
    if text is None:
        return None
    parts = text.split(":")
    try:
        if len(parts) != 3:
            raise ValueError
        return float(parts[0]), float(parts[1]), int(parts[2])
    except ValueError:
        raise TwinInputError("--rpm", text, "give MIN:MAX:N, e.g. 5000:25000:200") from None


@app.command()
@_guard
def lobes(
    scenario: str = typer.Argument(..., help="Scenario TOML file, or a bundled scenario name"),
    method: str = typer.Option("both", "--method", help="zoa | sd | both"),
    rpm: str = typer.Option(None, "--rpm", help="Spindle speeds MIN:MAX:N (default: from the scenario's)"),
    depth_max: float = typer.Option(None, "--depth-max", help="Deepest depth the semi-discretization scans, mm"),
    immersion: float = typer.Option(None, "--immersion", help="Radial immersion a_e/D in (0, 1] (default: a slot)"),
    down: bool = typer.Option(None, "--down/--up", help="Down (climb) or up (conventional) milling"),
    tool: int = typer.Option(None, "--tool", help="The tools entry of this T number"),
    feed_per_tooth: float = typer.Option(0.1, "--feed-per-tooth", help="Chip of a Kienzle material, mm"),
    sets: list[str] = typer.Option(None, "--set", help="Change a field: PATH=VALUE"),
    as_json: bool = typer.Option(False, "--json", help="Print the lobes as JSON"),
    plots: Path = typer.Option(None, "--plots", help="Write the lobes (PNG) to this folder"),
):
    """Stability lobes of the scenario's tool (its dynamics table): the critical axial depth
    against spindle speed by the zero-order solution and semi-discretization, and with a stock
    and a program every cutting line checked against them."""
    from twin import api
    from twin.settings import parse_settings

    _check_folder(plots)
    mode = None if down is None else ("down" if down else "up")
    found = api.lobes(
        scenario,
        method=method,
        rpm=_parse_rpm(rpm),
        depth_max_mm=depth_max,
        immersion=immersion,
        mode=mode,
        tool_number=tool,
        feed_per_tooth_mm=feed_per_tooth,
        **parse_settings(sets or []),
    )
    summary = found.summary
    if as_json:
        _echo_json(summary, 1)
    else:
        typer.echo(
            f"{summary['scenario']}: {summary['tool']}, {summary['n_flutes']} flutes, D {summary['diameter_mm']:g} mm, "
            f"{summary['material']} (K_t {summary['K_t_N_per_mm2']:g} N/mm^2, K_r {summary['K_r']:.3g}), "
            f"a_e/D {summary['immersion']:g} {summary['mode']} milling, {summary['dynamics']}"
        )
        for name, low in summary["lowest"].items():
            rows = summary["lobes"][name]
            span = f"{rows[0]['spindle_rpm']:g}-{rows[-1]['spindle_rpm']:g} rpm ({len(rows)} speeds)"
            where = (
                "no boundary"
                if low is None
                else (f"lowest critical depth {low['critical_depth_mm']:.3f} mm at {low['spindle_rpm']:.0f} rpm")
            )
            typer.echo(f"  {name}: {where} over {span}, {summary['seconds'][name]:.2f} s")
        _print_chatter_check(summary.get("lines", []))
    if plots is not None:
        plots.mkdir(parents=True, exist_ok=True)
        path = found.write_png(plots / f"lobes_{Path(scenario).stem}.png")
        typer.echo(f"plot written to {path}", err=as_json)


@app.command()
@_guard
def calibrate(
    machine: str = typer.Argument(..., help="A machine (twin list) or a machine file (FILE.toml)"),
    trace: Path = typer.Option(..., "--trace", help="Measured time trace or FRF, .csv or .parquet"),
    fit: str = typer.Option(..., "--fit", help="Parameters to fit, SYM,SYM"),
    axis: str = typer.Option("x", "--axis", help="The axis an FRF was measured on"),
    sensor: str = typer.Option("table", "--sensor", help="motor | table: where an FRF was measured"),
    sets: list[str] = typer.Option(
        None,
        "--set",
        help="Parameter override SYMBOL=VALUE before the fit; timestep_s=S: the physics step of the fit's twin runs",
    ),
    as_json: bool = typer.Option(False, "--json", help="Print the result as JSON"),
    out: Path = typer.Option(None, "--out", help="Write the calibrated machine file (.toml; machine files only)"),
):
    """Fit named machine parameters to a measured time trace or FRF (least squares through the
    twin), with standard errors and the fit index before and after."""
    from twin import api
    from twin.machines import get_machine
    from twin.results import check_calibrated_output

    _check_output("--out", out, ".toml")
    if out is not None:  # before the fit's minutes
        check_calibrated_output(machine, "--out", out)
    symbols = [s.strip() for s in fit.split(",") if s.strip()]
    timestep, overrides = _timestep_and_sets(sets or [])
    calibration = api.calibrate(
        machine,
        trace,
        symbols,
        overrides=overrides,
        axis=axis,
        sensor=sensor,
        progress=not as_json,
        timestep_s=timestep,
    )
    if as_json:
        _echo_json(calibration.summary, 2)
    else:
        report = calibration.report
        what = "twin runs" if report.kind == "time" else "model evaluations"
        typer.echo(f"{machine}: {report.kind} trace {trace}, {report.evaluations} {what}")
        solver = report.solver
        typer.echo(
            f"  {'converged' if solver.converged else 'NOT converged'}: {solver.termination} "
            f"(optimality {solver.optimality:.2g}"
            + (f", {solver.rejected_diverged} diverging trials rejected)" if solver.rejected_diverged else ")")
        )
        for s, v in report.fitted.items():
            unit = get_machine(machine).parameters[s].unit
            error = report.standard_errors.get(s)
            spread = f" +- {error:.2g}" if error is not None else " (no standard error: the fit did not converge)"
            if s in report.model_errors:
                spread += f" (noise {report.statistical_errors[s]:.2g}, model {report.model_errors[s]:.2g})"
            typer.echo(f"  {s} = {v:.6g} {unit}{spread} (nominal {report.nominal[s]:.6g})")
        for s, why in report.unidentifiable.items():
            typer.echo(f"  {s}: not identifiable, kept at {report.nominal[s]:.6g}: {why}")
        for s, why in report.poorly_determined.items():
            typer.echo(f"  {s}: poorly determined: {why}")
        typer.echo("  fit index: " + ", ".join(f"{k} {v:.2f} %" for k, v in report.fit_index_pct.to_json().items()))
        noise = solver.against_noise
        if noise is not None:
            typer.echo(
                f"  residual {noise.residual_rms_m:.3g} m RMS, the trace's noise {noise.noise_floor_m:.3g} m: "
                + noise.note
            )
        for s, why in report.not_excited.items():
            typer.echo(f"  {s}: not excited: {why}")
    if out is not None:
        calibration.write_machine_file(out)
        typer.echo(f"calibrated machine file written to {out}", err=as_json)


@app.command()
@_guard
def excite(
    machine: str = typer.Argument(..., help="A machine (twin list) or a machine file (FILE.toml)"),
    out: Path = typer.Option(..., "--out", help="The trace to write, .csv or .parquet"),
    axis: str = typer.Option("x", "--axis", help="The axis to excite"),
    f_max: float = typer.Option(500.0, "--f-max", help="Highest frequency excited, Hz (1.5 x the highest mode)"),
    amplitude: float = typer.Option(2.0, "--amplitude", help="PRBS amplitude, V"),
    duration: float = typer.Option(0.6, "--duration", help="Length, s (an open loop drifts: keep it short)"),
    seed: int = typer.Option(1, "--seed", help="Random seed of the PRBS"),
    simulate: bool = typer.Option(False, "--simulate", help="Add the twin's open-loop response (pos_<axis>_m)"),
    sets: list[str] = typer.Option(None, "--set", help="Parameter override SYMBOL=VALUE (with --simulate)"),
):
    """Write an open-loop PRBS for calibration (time_s, u_<axis>_V at 0.1 ms): play it on the
    machine, add the measured pos_<axis>_m and give it to twin calibrate --trace; --simulate adds
    the twin's own response instead."""
    from twin.commissioning.calibration import excitation_trace, write_table

    if out.suffix not in (".csv", ".parquet"):
        raise TwinInputError("--out", str(out), "must be a .csv or .parquet file")
    _check_output("--out", out)
    columns = excitation_trace(
        machine, axis, f_max, amplitude, duration, seed, _parse_sets(sets or []), simulate_twin=simulate
    )
    write_table(columns, out)
    typer.echo(
        f"{out}: {len(columns['time_s'])} samples, PRBS of {amplitude:g} V on {axis} to about {f_max:g} Hz"
        + (", with the twin's response" if simulate else f": record pos_{axis}_m beside it")
    )


@app.command()
@_guard
def tune(
    machine: str = typer.Argument(..., help="A machine (twin list) or a machine file (FILE.toml)"),
    sets: list[str] = typer.Option(None, "--set", help="Parameter override SYMBOL=VALUE"),
    control_period: float = typer.Option(None, "--control-period", help="Control period, s (default about 0.1 ms)"),
    feedback: str = typer.Option(
        None,
        "--feedback",
        help="dual | table | motor: velocity on the motor and position on the table's scale, both on the "
        "scale, or both on the motor (default: the machine's, dual for a machine file)",
    ),
    as_json: bool = typer.Option(False, "--json", help="Print the design as JSON"),
    out: Path = typer.Option(None, "--out", help="Write the tuned cascade as a scenario (.toml, a 10 mm circle)"),
    check: bool = typer.Option(True, "--verify/--no-verify", help="Run a step and a circle on the twin"),
    check_margins: bool = typer.Option(
        False,
        "--verify-margins",
        help="Bisect each gain's stability boundary on the twin (as run, without Coulomb friction, linear at the "
        "machine's physics step and a quarter of it) and print it beside the cascade margin",
    ),
):
    """Design each axis's position P / velocity PI cascade with feedforward and a notch or
    low-pass where a resonance needs it (phase margin >= 45 deg, gain margin >= 6 dB on the
    sampled loop with its delay), verify it on the twin and write it as a scenario."""
    from twin import api

    _check_output("--out", out, ".toml")
    if control_period is not None and not (1e-6 <= control_period <= 0.1):
        raise TwinInputError("--control-period", control_period, "must be in [1e-6, 0.1] s")
    tuned = api.tune(machine, _parse_sets(sets or []), control_period, feedback)
    if check:
        tuned.verify()
    if check_margins:
        tuned.verify_margins()
    result = tuned.summary
    if as_json:
        _echo_json(result, 2)
    else:
        typer.echo(f"{machine}: control period {1e3 * result['control_period_s']:g} ms, {result['feedback']} feedback")
        for a, r in result["axes"].items():
            g = r["gains"]
            filt = (
                f"notch {g['notch_hz']:.1f} Hz"
                if g["notch_hz"]
                else (f"low-pass {g['lowpass_hz']:.0f} Hz" if g["lowpass_hz"] else "no filter")
            )
            typer.echo(
                f"  {a}: kp {g['kp_pos']:.4g} 1/s, kv {g['kp_vel']:.4g} V s/m, "
                f"Ti {1e3 * g['ti_vel_s']:.3g} ms, {filt}; "
                f"velocity loop {r['velocity_loop']['crossover_hz']:.1f} Hz, "
                f"position bandwidth {r['bandwidth_hz']:.1f} Hz, "
                f"PM {r['phase_margin_deg']:.1f} deg, "
                f"GM {_gain_margin(r['velocity_loop'])} (velocity loop), {_gain_margin(r['position_loop'])} (position)"
            )
            cascade = r["cascade_margins"]
            typer.echo(
                "     whole cascade, the gain increase to instability: "
                + ", ".join(f"{k} {_gain_margin(cascade[k])}" for k in ("kp_pos", "kp_vel", "ki_vel"))
            )
        for a, v in result.get("verification", {}).items():
            typer.echo(f"  verified on the twin, {a}: " + ", ".join(f"{k} {x:.4g}" for k, x in v.items()))
        if check_margins:
            from twin.commissioning.boundary import CONDITIONS, MAX_WIDENINGS

            typer.echo(
                "  the twin's bisected boundary, dB (less the cascade margin): "
                + ", ".join(CONDITIONS)
                + ", zero step (the linear boundary extrapolated to a zero physics step)"
            )

            def found(boundary: float | None, less: float | None) -> str:
                return f"none within {MAX_WIDENINGS} dB" if boundary is None else f"{boundary:6.2f} ({less:+.2f})"

            for row in result["margin_check"]:
                typer.echo(
                    f"  {row['axis']} {row['gain']:<7} margin {row['margin_db']:6.2f} dB: "
                    + ", ".join(
                        found(row[name] and row[name]["boundary_db"], row[name + "_minus_margin_db"])
                        for name in CONDITIONS
                    )
                    + ", "
                    + (
                        "-"
                        if row.get("zero_step_db") is None
                        else found(row["zero_step_db"], row["zero_step_minus_margin_db"])
                    )
                )
    if out is not None:
        out.write_text(tuned.scenario_text(), encoding="utf-8")
        typer.echo(f"scenario written to {out} (run it: twin run {out})", err=as_json)


@app.command()
@_guard
def mjcf(
    machine: str = typer.Argument(..., help="A machine (twin list) or a machine file (FILE.toml)"),
    out: Path = typer.Option(..., "--out", help="The MJCF to write (.xml)"),
    sets: list[str] = typer.Option(None, "--set", help="Parameter override SYMBOL=VALUE"),
    timestep: float = typer.Option(None, "--timestep", help="Physics step, s (default the machine's)"),
):
    """Write the MuJoCo model (MJCF) the twin simulates for a machine, its values written in,
    for use in one's own MuJoCo code."""
    from twin.machines import get_machine
    from twin.scenario import MAX_TIMESTEP_S, MIN_TIMESTEP_S

    _check_output("--out", out, ".xml")
    if timestep is not None and not (MIN_TIMESTEP_S <= timestep <= MAX_TIMESTEP_S):
        raise TwinInputError("--timestep", timestep, f"must be in [{MIN_TIMESTEP_S:g}, {MAX_TIMESTEP_S:g}] s")
    out.write_text(get_machine(machine).mjcf(_parse_sets(sets or []), timestep))
    typer.echo(f"wrote {out}")


@app.command("list")
def list_things():
    """Machines, controller kinds, observers, disturbances, materials, references, bundled
    scenarios and reproducible papers."""
    from controllers import CONTROLLERS, OBSERVERS
    from twin.disturbances import DISTURBANCES
    from twin.machines import MACHINES
    from twin.machining.materials import KIENZLE_AXIAL_RATIO, KIENZLE_RADIAL_RATIO, MATERIALS
    from twin.references import REFERENCES
    from twin.reproductions.registry import REPRODUCTIONS
    from twin.scenario import bundled_scenarios, load_scenario

    def params(kind):
        names = list(kind.params.model_fields)
        return f" [params: {', '.join(names)}]" if names else ""

    typer.echo("machines (or a machine file of datasheet values, FILE.toml: examples/machines/):")
    for name, m in MACHINES.items():
        typer.echo(f"  {name:<22} {m.summary}")
    typer.echo("controllers (type = ...):")
    for name, kind in CONTROLLERS.items():
        typer.echo(f"  {name:<22} {kind.doc}{params(kind)}")
    typer.echo("observers ([controller.observer] type = ...):")
    for name, kind in OBSERVERS.items():
        typer.echo(f"  {name:<22} {kind.doc}{params(kind)}")
    typer.echo("disturbances ([[disturbances]] type = ...):")
    for name, kind in DISTURBANCES.items():
        typer.echo(f"  {name:<22} {kind.doc.removeprefix(name + ': ')}")
    typer.echo(
        "materials ([tool] / [[tools]] / end_milling material = ...): linear K_tc K_rc K_ac N/mm^2, K_te K_re K_ae"
        f" N/mm; Kienzle kc1 N/mm^2 and mc (kc = kc1 h^-mc), radial and axial {KIENZLE_RADIAL_RATIO:g} and"
        f" {KIENZLE_AXIAL_RATIO:g} of the tangential (our ratios, no source)"
    )
    for name, material in MATERIALS.items():
        k = material.coefficients
        if k.mc:
            values = f"kc1 {k.K_tc:.0f}, mc {k.mc:.3f}"
        else:
            values = f"{k.K_tc:g} {k.K_rc:g} {k.K_ac:g}, {k.K_te:g} {k.K_re:g} {k.K_ae:g}"
        typer.echo(
            f"  {name:<24} {material.model}: {material.alloy}, {material.cutter}, {material.lubrication}: {values}"
            f" ({material.source})"
        )
    typer.echo("references ([reference] type = ...):")
    for name, kind in REFERENCES.items():
        typer.echo(f"  {name:<22} {kind.doc.removeprefix(name + ': ')}")
    typer.echo("scenarios:")
    for name in sorted(bundled_scenarios()):
        typer.echo(f"  {name:<30} {load_scenario(name).description}")
    typer.echo("reproductions (twin reproduce ...):")
    for name, paper in REPRODUCTIONS.items():
        typer.echo(f"  {name:<22} {paper.doc}")


@app.command()
@_guard
def bench(
    as_json: bool = typer.Option(False, "--json", help="Print the figures as JSON"),
    seconds: float = typer.Option(2.0, help="Simulated time per measurement (s)"),
    repeats: int = typer.Option(None, help="Alternating repeats; medians are reported (default 5; --sweep: 1)"),
    sweep: bool = typer.Option(False, "--sweep", help="Benchmark twin sweep instead (twin/sweeps/bench.py)"),
    samples: int = typer.Option(1000, "--samples", help="--sweep: samples of 2 s of the cutting circle"),
    memory_samples: int = typer.Option(
        10_000, "--memory-samples", help="--sweep: one-tick samples for the client memory check"
    ),
    gcode_lines: int = typer.Option(1_000_000, "--gcode-lines", help="Lines of the G-code reader's program"),
    gcode_moves: int = typer.Option(10_000, "--gcode-moves", help="Moves of the planner's and engagement's program"),
    finish_lines: int = typer.Option(
        17_000, "--finish-lines", help="Lines of the generated ball finishing program of the part's figures"
    ),
    part_repeats: int = typer.Option(
        3, "--part-repeats", help="Alternating repeats of the virtual part's cases (0: leave the part out)"
    ),
    planning_only: bool = typer.Option(
        False, "--planning-only", help="Only the planner's speed against the motion it plans"
    ),
    planning_scale: float = typer.Option(
        1.0, "--planning-scale", help="Factor on the planning programs' lengths (lines, turns; 0: leave them out)"
    ),
    planning_file: Path = typer.Option(None, "--planning-file", help="A part program to plan too"),
    against: str = typer.Option(
        None, "--against", help="Time the closed-loop cases of commit REV (A) and this checkout (B) alternately"
    ),
    case: list[str] = typer.Option(None, "--case", help="--against: a case to time (repeat it; default all)"),
):
    """Steps per second, bare mj_step vs the closed loop, for four controller kinds and a part
    program, start-up time, the G-code reader's lines/s and the planner's time (twin/bench.py);
    with --sweep, twin sweep's wall time, samples/s, parallel efficiency and memory; with
    --against REV, the closed-loop cases of REV's tree and this checkout's, alternately, and
    their ratio (twin/bench_against.py)."""
    from twin.bench import run_bench

    if not (seconds > 0 and seconds <= 600):
        raise TwinInputError("--seconds", seconds, "must be in (0, 600]")
    repeats = repeats if repeats is not None else 1 if sweep else 15 if against is not None else 5
    if not 1 <= repeats <= 100:
        raise TwinInputError("--repeats", repeats, "must be in 1..100")
    if not 2 <= gcode_lines <= 10_000_000:
        raise TwinInputError("--gcode-lines", gcode_lines, "must be in 2..10000000")
    if not 2 <= gcode_moves <= 100_000:
        raise TwinInputError("--gcode-moves", gcode_moves, "must be in 2..100000")
    if not 2 <= finish_lines <= 1_000_000:
        raise TwinInputError("--finish-lines", finish_lines, "must be in 2..1000000")
    if not 0 <= part_repeats <= 100:
        raise TwinInputError("--part-repeats", part_repeats, "must be in 0..100")
    if not (planning_scale == 0 or 1e-3 <= planning_scale <= 10.0):
        raise TwinInputError("--planning-scale", planning_scale, "must be 0 (leave planning out) or in [0.001, 10]")
    if planning_file is not None and not planning_file.is_file():
        raise TwinInputError("--planning-file", str(planning_file), "is not a file")
    if case and against is None:
        raise TwinInputError("--case", case[0], "is for --against only")
    if against is not None:
        _bench_against(as_json, against, case or [], seconds, repeats)
        return
    if sweep:
        _bench_sweep(as_json, samples, memory_samples, repeats)
        return
    file = str(planning_file) if planning_file else None
    if planning_only:
        from twin.bench import planning_figures

        planning = planning_figures(planning_scale or 1.0, file)
        if as_json:
            _echo_json({"planning": planning}, 2)
        else:
            _print_planning_bench(planning)
        return
    figures = run_bench(seconds, repeats, gcode_lines, gcode_moves, finish_lines, part_repeats, planning_scale, file)
    if as_json:
        _echo_json(figures, 2)
        return
    typer.echo(f"medians of {repeats} alternating repeats, {seconds:g} s simulated each")
    typer.echo(f"{'case':<30} {'bare steps/s':>14} {'closed steps/s':>15} {'ratio':>6} {'x realtime':>11}  loop")
    for name, f in figures["cases"].items():
        typer.echo(
            f"{name:<30} {f['raw_steps_per_s']:>14,.0f} {f['closed_loop_steps_per_s']:>15,.0f} "
            f"{f['ratio']:>6.3f} {f['realtime_factor']:>11.1f}  {f['loop']}"
        )
    f = figures["startup"]
    typer.echo(
        f"start-up: twin run {f['scenario']} {f['run_process_s']:.2f} s as a new process, "
        f"{f['run_in_process_s']:.2f} s in process, overhead {f['overhead_s']:.2f} s; "
        f"twin --help {f['help_process_s']:.2f} s"
    )
    g = figures["gcode"]
    typer.echo(
        f"G-code: read {g['gcode_lines']:,} CAM-like lines at {g['read_lines_per_s']:,.0f} lines/s; "
        f"planned {g['plan_moves']:,} moves in {g['plan_s']:.2f} s ({g['plan_moves_per_s']:,.0f} moves/s, "
        f"cycle time {g['plan_cycle_time_s']:.0f} s), their engagement in {g['engagement_s']:.2f} s; "
        "the streamed plan's peak memory "
        + ", ".join(f"{mb:.1f} MB for {length} s" for length, mb in g["stream_peak_mb"].items())
        + "; a run's "
        + ", ".join(f"{mb:.1f} MB for {length} s" for length, mb in g["run_peak_mb"].items())
    )
    if figures["part"] is not None:
        _print_part_bench(figures["part"])
    if figures["planning"] is not None:
        _print_planning_bench(figures["planning"])


def _print_planning_bench(planning: dict) -> None:
    """``twin bench``'s planning figures: motion time over the planner's CPU time per program
    and limits (issue 46: at least 100)."""
    typer.echo(f"{'planning':<30} {'limits':<20} {'motion s':>10} {'plan CPU s':>11} {'motion/plan':>12}")
    for name, by_limits in planning.items():
        for limits, f in by_limits.items():
            typer.echo(
                f"{name[-30:]:<30} {limits:<20} {f['motion_s']:>10.1f} {f['plan_cpu_s']:>11.2f} {f['ratio']:>12.0f}"
                + (f"  ({f['violations']} over a limit)" if f["violations"] else "")
            )
    typer.echo("target (issue 46): motion/plan >= 100 at any limits")


def _print_part_bench(part: dict) -> None:
    """``twin bench``'s virtual part figures: each case's run beside its part, and the finishing
    program's."""
    typer.echo(f"{'virtual part':<30} {'ticks':>8} {'run s':>8} {'part s':>8} {'part/run':>9} {'part peak MB':>13}")
    for name, f in part["cases"].items():
        typer.echo(
            f"{name:<30} {f['ticks']:>8,} {f['run_s']:>8.2f} {f['part_s']:>8.2f} "
            f"{f['part_over_run']:>9.2f} {f['part_peak_mb']:>13.1f}"
        )
    typer.echo("targets (issue 45): part/run <= 1, part peak < 1000 MB, slot_four_passes part < 10 s")
    f = part["finish"]
    typer.echo(
        f"ball finishing program: {f['lines']:,} lines, {f['samples']:,} samples ({f['cycle_time_s']:.0f} s of motion) "
        f"at {f['resolution_mm']:g} mm cells: planned in {f['plan_s']:.1f} s, engagement {f['engagement_s']:.1f} s "
        f"(peak {f['plan_and_engagement_peak_mb']:.0f} MB), part {f['part_s']:.1f} s (peak {f['part_peak_mb']:.0f} MB)"
    )


def _bench_against(as_json: bool, rev: str, cases: list[str], seconds: float, repeats: int) -> None:
    """``twin bench --against REV``: each case's closed-loop steps/s in REV's tree (A) and this
    checkout (B), timed alternately, and the median ratio B/A."""
    from twin.bench_against import compare

    f = compare(rev, cases, seconds, repeats)
    if as_json:
        _echo_json(f, 2)
        return
    edited = " with uncommitted edits" if f["b_modified"] else ""
    typer.echo(
        f"A = {rev} ({f['a_commit'][:10]}), B = this checkout ({f['b_commit'][:10]}{edited}); "
        f"medians of {repeats} alternating pairs, {seconds:g} s simulated each"
    )
    typer.echo(
        f"{'case':<30} {'A steps/s':>11} {'B steps/s':>11} {'B/A':>6} {'B/A CPU':>8} "
        f"{'A closed/bare':>14} {'B closed/bare':>14}"
    )
    for name, c in f["cases"].items():
        typer.echo(
            f"{name:<30} {c['a']['closed_loop_steps_per_s']:>11,.0f} {c['b']['closed_loop_steps_per_s']:>11,.0f} "
            f"{c['b_over_a']:>6.3f} {c['b_over_a_cpu']:>8.3f} {c['a']['ratio']:>14.3f} {c['b']['ratio']:>14.3f}"
        )
    for tree in ("a", "b"):
        if f[f"only_in_{tree}"]:
            typer.echo(f"only in {tree.upper()} (not timed): {', '.join(f[f'only_in_{tree}'])}")


def _bench_sweep(as_json: bool, samples: int, memory_samples: int, repeats: int) -> None:
    from twin.sweeps.bench import run_sweep_bench

    for option, value in (("--samples", samples), ("--memory-samples", memory_samples)):
        if not 1 <= value <= 100_000:
            raise TwinInputError(option, value, "must be in 1..100000")
    f = run_sweep_bench(samples, repeats, memory_samples, progress=not as_json)
    if as_json:
        _echo_json({"sweep": f}, 2)
        return
    typer.echo(
        f"twin sweep {f['scenario']} ({', '.join(f['settings'])}) --vary {' --vary '.join(f['vary'])}, "
        f"{f['samples']} samples, median of {f['repeats']}:"
    )
    typer.echo(
        f"  1 worker {f['wall_s_1_worker']:.1f} s, 2 workers {f['wall_s_2_workers']:.1f} s "
        f"(target <= {f['target_wall_s']:g} s), {f['samples_per_s_2_workers']:.1f} samples/s; parallel "
        f"efficiency {f['parallel_efficiency']:.3f} (target >= {f['target_efficiency']:g})"
    )
    typer.echo(
        f"  client memory grew {f['client_memory_growth_MB']:.1f} MB over {f['memory_samples']} one-tick samples"
    )
    typer.echo(
        f"  a plain loop over twin run processes: {f['twin_run_loop_s_per_sample']:.2f} s per sample "
        f"({f['twin_run_loop_samples']} timed), {f['twin_run_loop_extrapolated_s']:.0f} s for "
        f"{f['samples']} samples"
    )


def _terminate(signum, frame):
    """SIGTERM ends a run as Ctrl-C does: what was computed is kept and reported."""
    raise KeyboardInterrupt


def run_cli(argv: list[str]) -> int:
    """Run the command line ``argv`` (without the program's name) and return its exit code
    (:mod:`twin.exits`); a usage error (an unknown option, a value of the wrong type, a missing
    argument) is one ``error:`` line with exit code 2, as any other bad input."""
    try:
        code = app(args=argv, prog_name="twin", standalone_mode=False)
    except typer.Abort:
        typer.echo("error: interrupted", err=True)
        return exits.INTERRUPTED
    except Exception as exc:
        if not hasattr(exc, "format_message"):  # click's usage errors (typer carries its own click)
            typer.echo(exits.internal_error_line(exc), err=True)
            return exits.INTERNAL_ERROR
        context = getattr(exc, "ctx", None)
        command = context.command_path if context is not None else "twin"
        message = " ".join(exc.format_message().split())
        typer.echo(f"error: {command}: {message} (see {command} --help)", err=True)
        return exits.BAD_INPUT
    return code if isinstance(code, int) else exits.DONE


def main() -> None:
    """The command line (:mod:`twin.launcher` runs it for every command but a plain listing)."""
    signal.signal(signal.SIGTERM, _terminate)
    try:
        code = run_cli(sys.argv[1:])
        sys.stdout.flush()
    except BrokenPipeError:
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())  # Python's flush at exit goes nowhere
        code = exits.PIPE_CLOSED
    sys.exit(code)


if __name__ == "__main__":
    main()
