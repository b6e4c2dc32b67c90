"""``twin gcode``: a part program read as LinuxCNC reads it and, with a machine, planned."""

from __future__ import annotations

from pathlib import Path

import typer

from twin.cli.common import _guard
from twin.cli.printing import _fail_on_warnings, _print_summary, _print_warnings


@_guard
def gcode(
    *,
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
    warnings, total = planned.warnings, planned.warnings_total
    if not as_json:
        typer.echo(f"planned for {machine}:")
        _print_summary("", planned.headline())
        for over in planned.violations:
            typer.echo(f"  over a limit: {over.report_line()}")
        for note in planned.notes:
            typer.echo(f"  note: {note}")
        for axis in "xyz":
            typer.echo(f"  {planned.axis_line(axis)}")
        _print_warnings("warnings against the machine", warnings, total)
    if strict:
        _fail_on_warnings("warning(s) against the machine", warnings, total)
