"""The commands that run scenarios and list what the twin offers: ``twin run | demo | fidelity |
reproduce | sweep | mjcf | list``."""

from __future__ import annotations

from pathlib import Path

import typer

from twin import exits
from twin.cli.common import _check_folder, _check_output, _echo_json, _guard, _parse_sets
from twin.cli.printing import (
    _fail_on_warnings,
    _print_chatter,
    _print_chatter_check,
    _print_part,
    _print_summary,
    _print_warnings,
    _print_worst_lines,
)
from twin.errors import TwinInputError
from twin.reproductions import DEFAULT_SAMPLES, DEFAULT_SEED, DEFAULT_TWIN_SAMPLES


def _run(
    scenario: str,
    *,
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
    _report(
        done, rrd=rrd, as_json=as_json, plots=plots, lines=lines, part=part
    )  # a run that stopped early too: what it computed
    if done.stopped is not None:
        raise done.stopped
    if strict:
        records = done.records  # what the report printed, not computed again
        _fail_on_warnings("machining warning(s)", records.machining_warnings, records.machining_warnings_total)
        _fail_on_warnings("warning(s) against the machine", records.plan_warnings, records.plan_warnings_total)
        chatter = records.chatter_warnings
        _fail_on_warnings("chatter warning(s)", chatter, len(chatter))


def _report(
    done,
    *,
    rrd: Path | None,
    as_json: bool,
    plots: Path | None,
    lines: Path | None = None,
    part: Path | None = None,
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
        _print_chatter_check(records.stability_checks)
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
    if part is not None and done.outcome.part is not None:
        for path in done.write_part(part):
            typer.echo(f"part written to {path}", err=as_json)


@_guard
def run(
    *,
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
    _run(
        scenario,
        rrd=rrd,
        as_json=as_json,
        settings=sets,
        max_steps=max_steps,
        plots=plots,
        lines=lines,
        strict=strict,
        part=part,
    )


@_guard
def demo(
    rrd: Path = typer.Option(Path("demo.rrd"), "--rrd", help="Rerun recording to write"),
    as_json: bool = typer.Option(False, "--json", help="Print metrics as JSON"),
    plots: Path = typer.Option(None, "--plots", help="Write PNG plots to this folder"),
):
    """The main job: Choi 1999's cutting circle (R 28 mm, 4800 mm/min, 10000 rpm end milling) on the
    linear-motor table under the MIMO H-infinity loop-shaping controller with ZPETC."""
    _run("choi1999_mimo_cutting", rrd=rrd, as_json=as_json, plots=plots)


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


@_guard
def reproduce(
    *,
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


@_guard
def sweep(
    *,
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


def list_things():
    """Machines, controller kinds, observers, disturbances, materials, references, inspection
    features, bundled scenarios and reproducible papers (the catalogue, :mod:`twin.catalogue`)."""
    from twin.catalogue import list_lines

    for line in list_lines():
        typer.echo(line)
