"""The command line's contract: what each exit code means, warnings kept from the user, and
JSON that is strict.

=====  ==============================================================================
code   meaning
=====  ==============================================================================
0      done
2      bad input: one ``error:`` line naming the field (or file:line), value and reason;
       nothing on stdout
3      the simulation diverged: one ``error:`` line with the simulated time; what was
       computed before it is reported (``twin run``)
4      a check ran and failed (``twin fidelity``, ``twin reproduce``, ``twin run
       --strict``): the report, then one ``error:`` line
70     a bug of the twin (an exception it does not expect, or a numerical warning that
       reached the command): one ``error: internal error`` line; the fuzz tests look for it
130    interrupted (Ctrl-C, SIGTERM): what was computed is reported
141    stdout closed early (``twin gcode FILE | head``): quiet
=====  ==============================================================================

Exit code 1 and tracebacks never happen.  Every warning from numpy, scipy, python-control,
numba or MuJoCo becomes an exception inside a command (a number the twin did not bound), which
ends it with code 70 rather than a warning line and a result computed from an overflow;
warnings addressed to the twin's developers (deprecations) are not shown.
"""

from __future__ import annotations

import json
import math
import sys
import traceback
import warnings
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path

DONE = 0
BAD_INPUT = 2
DIVERGED = 3
CHECK_FAILED = 4
INTERNAL_ERROR = 70
INTERRUPTED = 130
PIPE_CLOSED = 141


@contextmanager
def warnings_as_errors() -> Iterator[None]:
    """Every warning raised inside becomes an exception, but those meant for developers
    (deprecations), which are ignored."""
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        for category in (DeprecationWarning, PendingDeprecationWarning, FutureWarning):
            warnings.simplefilter("ignore", category)
        yield


def report(exc: BaseException) -> int:
    """The exit code of the exception ``exc`` that ended a command, with its one ``error:``
    line written on stderr: the twin's own errors (bad input, a divergence, an interruption),
    Ctrl-C, a file the system would not read or write (bad input: a full disk, no permission),
    and anything else as a bug."""
    from twin.errors import RunInterrupted, SimulationDiverged, TwinInputError

    if isinstance(exc, TwinInputError):
        code, line = BAD_INPUT, f"error: {exc}"
    elif isinstance(exc, SimulationDiverged):
        code, line = DIVERGED, f"error: {exc}"
    elif isinstance(exc, RunInterrupted):
        code, line = INTERRUPTED, f"error: {exc}"
    elif isinstance(exc, KeyboardInterrupt):
        code, line = INTERRUPTED, "error: interrupted"
    elif isinstance(exc, OSError) and exc.filename is not None:
        code, line = BAD_INPUT, f"error: {TwinInputError('file', str(exc.filename), exc.strerror or str(exc))}"
    else:
        code, line = INTERNAL_ERROR, internal_error_line(exc)
    print(line, file=sys.stderr)
    return code


def internal_error_line(exc: BaseException) -> str:
    """The one line for an exception the twin does not expect: its type, message and the
    twin's innermost line it passed through."""
    root = Path(__file__).resolve().parent.parent
    where = ""
    for frame in reversed(traceback.extract_tb(exc.__traceback__)):
        path = Path(frame.filename).resolve()
        if path.is_relative_to(root) and ".venv" not in path.parts:
            where = f" at {path.relative_to(root)}:{frame.lineno}"
            break
    message = " ".join(str(exc).split())[:300]
    return (
        f"error: internal error, a bug of the twin: {type(exc).__name__}: {message}{where} "
        "(please report it with the command line and its input files)"
    )


def _finite_or_null(value, path: str, non_finite: dict[str, str]):
    """``value`` with every nan or infinite float replaced by None (JSON's null), recorded in
    ``non_finite`` as ``{path: "inf" | "-inf" | "nan"}``."""
    if isinstance(value, float) and not math.isfinite(value):
        non_finite[path or "."] = "nan" if math.isnan(value) else ("inf" if value > 0 else "-inf")
        return None
    if isinstance(value, dict):
        return {k: _finite_or_null(v, f"{path}.{k}" if path else str(k), non_finite) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_finite_or_null(v, f"{path}.{i}" if path else str(i), non_finite) for i, v in enumerate(value)]
    return value


def strict_json(value, indent: int = 1, default: Callable | None = None) -> str:
    """One strict JSON document (``allow_nan=False``): a non-finite float is written as null,
    and a dict gets a ``non_finite`` table naming each such value and what it was."""
    non_finite: dict[str, str] = {}
    ready = _finite_or_null(value, "", non_finite)
    if non_finite and isinstance(ready, dict):
        ready["non_finite"] = non_finite
    return json.dumps(ready, indent=indent, allow_nan=False, default=default)
