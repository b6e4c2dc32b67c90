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

import typer

from twin import exits
from twin.cli import bench, commissioning, gcode, run
from twin.cli.printing import SHOWN_WARNINGS, _print_warnings
from twin.cli.run import _report

__all__ = ["SHOWN_WARNINGS", "_print_warnings", "_report", "app", "main", "run_cli"]

app = typer.Typer(
    add_completion=False,
    pretty_exceptions_enable=False,
    no_args_is_help=True,
    help="Digital twin of CNC XY feed drives (MuJoCo).",
)

# the commands in the order --help lists them
app.command()(run.run)
app.command()(run.demo)
app.command()(run.fidelity)
app.command()(run.reproduce)
app.command()(run.sweep)
app.command()(gcode.gcode)
app.command()(commissioning.frf)
app.command()(commissioning.lobes)
app.command()(commissioning.calibrate)
app.command()(commissioning.excite)
app.command()(commissioning.tune)
app.command()(run.mjcf)
app.command("list")(run.list_things)
app.command()(bench.bench)


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
