"""The command line run inside the test process, as a subprocess would see it: exit code,
stdout and stderr (``twin.cli.run_cli``, which ``twin`` itself runs).  About 6 s faster per call
on 2 cores than ``python -m twin.cli``, whose start-up imports everything again; the few tests of
what only a real process shows (signals, start-up imports, the launcher) start one."""

from __future__ import annotations

import contextlib
import io
import os
import sys
from dataclasses import dataclass

from twin.cli import run_cli

#: The command line as a subprocess, for the tests that need a real process.
TWIN = [sys.executable, "-m", "twin.cli"]


@dataclass
class Completed:
    """What a finished command left: its exit code and its two streams."""

    returncode: int
    stdout: str
    stderr: str


def twin(*args, cwd=None) -> Completed:
    """Run ``twin ARGS`` in this process (in folder ``cwd`` if given) and return what it left."""
    out, err = io.StringIO(), io.StringIO()
    previous = os.getcwd()
    try:
        if cwd is not None:
            os.chdir(cwd)
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
            code = run_cli([str(a) for a in args])
    finally:
        os.chdir(previous)
    return Completed(code, out.getvalue(), err.getvalue())


def interruptible() -> None:
    """``preexec_fn`` of a subprocess that a test interrupts: SIGINT back to its default, which a
    shell's background job (and so a suite started with ``&``) would have ignored."""
    import signal

    signal.signal(signal.SIGINT, signal.SIG_DFL)
