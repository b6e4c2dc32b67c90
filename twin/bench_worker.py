"""One tree's bench cases, timed on request: the timing ``twin bench`` uses, and the worker process
``twin bench --against`` starts in each of the two trees it compares.

Run as a script (``python -P twin/bench_worker.py``, with the tree under test first on
``PYTHONPATH``), the worker imports that tree's ``twin.bench`` and builds its cases
(``_cases()``: name -> (machine, run(seconds))), warms up the ones named on its command line
(the compiled loop loaded or compiled), prints one JSON line ``{"ready": [names]}`` and then
answers each request line ``{"case": name, "seconds": s}`` with one JSON line ``{"bare_steps_per_s",
"closed_loop_steps_per_s", "loop"}`` from :func:`time_case`, until its input closes.  The timing is
this file's, the same for both trees; only the cases and the loop come from the tree under test.
Anything the tree prints goes to the worker's standard error: its standard output carries the
answers alone.
"""

from __future__ import annotations

import importlib
import json
import os
import sys
import time
from collections.abc import Callable
from typing import Any, NamedTuple

import mujoco


class Timing(NamedTuple):
    """One timing of a case (:func:`time_case`)."""

    #: Bare ``mj_step`` steps per wall second.
    bare_steps_per_s: float
    #: Closed-loop steps per wall second.
    closed_loop_steps_per_s: float
    #: The closed-loop run's result.
    result: Any
    #: Bare steps per second of this thread's CPU time (what a loaded machine's waits leave out).
    bare_steps_per_cpu_s: float
    #: Closed-loop steps per second of this thread's CPU time.
    closed_loop_steps_per_cpu_s: float


def bare_step_rates(model: Any, n: int) -> tuple[float, float]:
    """Bare ``mj_step`` (physics only, no controller, a constant 0.1 on every actuator) on
    ``model`` for ``n`` steps in one call; steps per wall second and per CPU second of this
    thread."""
    data = mujoco.MjData(model)
    data.ctrl[:] = 0.1
    t0, c0 = time.perf_counter(), time.thread_time()
    mujoco.mj_step(model, data, nstep=n)
    return n / (time.perf_counter() - t0), n / (time.thread_time() - c0)


def time_case(model: Any, run: Callable[[float], Any], seconds: float) -> Timing:
    """Bare ``mj_step`` on ``model`` and then the closed loop ``run(seconds)``, back to back.

    Parameters
    ----------
    model
        The case's ``mujoco.MjModel`` (its timestep sets the steps: ``seconds / timestep``).
    run
        The closed-loop run of ``seconds`` of simulated time (s); returns the run's result.
    seconds
        Simulated time of each timing (s).

    Returns
    -------
    Timing
        Bare and closed-loop steps per wall second and per CPU second, the run's result.
    """
    n = round(seconds / model.opt.timestep)
    bare, bare_cpu = bare_step_rates(model, n)
    t0, c0 = time.perf_counter(), time.thread_time()
    result = run(seconds)
    wall, cpu = time.perf_counter() - t0, time.thread_time() - c0
    return Timing(bare, n / wall, result, bare_cpu, n / cpu)


def serve(names: list[str]) -> None:
    """Build the tree's bench cases, warm up ``names`` and answer timing requests (module
    docstring) on standard input and output."""
    answers = os.fdopen(os.dup(sys.stdout.fileno()), "w", buffering=1)
    os.dup2(sys.stderr.fileno(), sys.stdout.fileno())  # the tree's own prints go to stderr

    # the tree under test's bench (first on PYTHONPATH), not this file's tree: imported by name
    cases = importlib.import_module("twin.bench")._cases()
    unknown = sorted(set(names) - set(cases))
    if unknown:
        answers.write(json.dumps({"unknown": unknown, "cases": list(cases)}) + "\n")
        return
    for name in names:
        cases[name][1](0.01)  # warm-up: the compiled loop loaded (or compiled)
    answers.write(json.dumps({"ready": names}) + "\n")
    for line in sys.stdin:
        request = json.loads(line)
        machine, run = cases[request["case"]]
        timing = time_case(machine.model, run, request["seconds"])
        answers.write(
            json.dumps(
                {
                    "bare_steps_per_s": timing.bare_steps_per_s,
                    "closed_loop_steps_per_s": timing.closed_loop_steps_per_s,
                    "bare_steps_per_cpu_s": timing.bare_steps_per_cpu_s,
                    "closed_loop_steps_per_cpu_s": timing.closed_loop_steps_per_cpu_s,
                    "loop": timing.result.info["loop"],
                }
            )
            + "\n"
        )


if __name__ == "__main__":
    serve(sys.argv[1:])
