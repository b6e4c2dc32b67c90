"""Helpers every command shares: the exit-code guard, strict JSON output, the checks of an
output path before any work, and ``--set SYMBOL=VALUE`` parsing."""

from __future__ import annotations

import os
from functools import wraps
from pathlib import Path

import typer

from twin import exits
from twin.errors import TwinInputError


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
