"""Errors the twin raises for bad input and for simulations that go wrong."""

from __future__ import annotations

import errno
import stat
from pathlib import Path
from typing import Any


class TwinInputError(ValueError):
    """Bad user input: names the field and the offending value.

    The CLI prints the message on one line and exits with code 2.
    """

    def __init__(self, field: str, value, reason: str):
        self.field = field
        self.value = value
        self.reason = reason
        super().__init__(f"{_short(field, 80)} = {_short(repr(value), 100)}: {_short(reason, 400)}")


def _short(text: str, limit: int) -> str:
    """One line: control characters escaped, at most ``limit`` characters."""
    text = "".join(c if c.isprintable() else repr(c)[1:-1] for c in str(text)).strip()
    return text if len(text) <= limit else text[: limit - 3] + "..."


def input_file(path: str | Path, field: str, missing: str = "no such file") -> Path:
    """``path`` if it names a regular file; else the twin's error under ``field``.

    Raises
    ------
    TwinInputError
        ``missing`` where nothing is there; a folder, a device or a pipe; a name the system
        cannot look up (too long, a loop of links, no permission), with its reason.
    """
    path = Path(path)
    try:
        mode = path.stat().st_mode
    except OSError as exc:
        reason = missing if exc.errno in (errno.ENOENT, errno.ENOTDIR) else (exc.strerror or str(exc))
        raise TwinInputError(field, str(path), reason) from None
    except ValueError as exc:  # a NUL character in the name
        raise TwinInputError(field, str(path), str(exc)) from None
    if stat.S_ISDIR(mode):
        raise TwinInputError(field, str(path), "is a folder")
    if not stat.S_ISREG(mode):
        raise TwinInputError(field, str(path), "is not a regular file (a device or a pipe)")
    return path


class SimulationDiverged(RuntimeError):
    """The physics blew up (non-finite state, MuJoCo instability warning or runaway).

    Attributes
    ----------
    sim_time_s : float
        Simulated time (s) at which the divergence was detected.
    result : twin.sim.runner.RunResult or None
        The run up to the last whole tick before it.
    """

    def __init__(self, sim_time_s: float, reason: str):
        self.sim_time_s = sim_time_s
        self.reason = reason
        # the run up to the divergence (a twin.sim.runner.RunResult), where the runner attaches it;
        # typed Any so that the errors, the floor every module stands on, import nothing above them
        self.result: Any = None
        super().__init__(f"simulation diverged at t = {sim_time_s:.6f} s: {_short(reason, 300)}")


class RunInterrupted(RuntimeError):
    """The user stopped a run (Ctrl-C or SIGTERM); ``result`` holds what was computed.

    Attributes
    ----------
    sim_time_s : float
        Simulated time (s) the run had reached.
    result : twin.sim.runner.RunResult
    """

    def __init__(self, sim_time_s: float, result):
        self.sim_time_s = sim_time_s
        self.result = result
        super().__init__(f"interrupted at t = {sim_time_s:.6f} s")
