"""The ``twin`` console script: ``twin gcode FILE [--json]`` (a program's listing, nothing
else on the line) is run with the reader alone, since the command line's parser (typer, with
the pydantic adapters it builds) takes about 0.1 s to import, as long as rs274 takes for a whole
15 000-line CAM program; every other command goes to :func:`twin.cli.main`."""

from __future__ import annotations

import os
import sys
from pathlib import Path


def plain_listing(argv: list[str]) -> tuple[Path, bool] | None:
    """The program file and whether JSON is asked for, for ``gcode FILE [--json]``; None for
    any other command line."""
    if argv[:1] != ["gcode"] or not 2 <= len(argv) <= 3:
        return None
    rest = argv[1:]
    as_json = "--json" in rest
    files = [a for a in rest if a != "--json"]
    if len(files) != 1 or files[0].startswith("-") or len(rest) - len(files) != int(as_json):
        return None
    return Path(files[0]), as_json


def main() -> None:
    """Console-script entry point. Errors are the command line's (:mod:`twin.exits`): one
    ``error: ...`` line on stderr, exit code 2 (bad input), 70 (a bug) or 130 (interrupted); a
    reader that closes the pipe early (``twin gcode FILE | head``) ends the listing quietly with
    exit code 141."""
    listing = plain_listing(sys.argv[1:])
    if listing is None:
        from twin.cli import main as cli_main

        cli_main()
        return
    from twin import exits
    from twin.gcode.listing import list_program
    from twin.gcode.reader import Settings

    file, as_json = listing
    try:
        with exits.warnings_as_errors():
            list_program(file, Settings(), as_json)
            sys.stdout.flush()
    except KeyboardInterrupt:
        print(f"error: interrupted while reading {file}; nothing was printed", file=sys.stderr)
        sys.exit(exits.INTERRUPTED)
    except BrokenPipeError:
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())  # Python's flush at exit goes nowhere
        sys.exit(exits.PIPE_CLOSED)
    except Exception as exc:
        sys.exit(exits.report(exc))


if __name__ == "__main__":
    main()
