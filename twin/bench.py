"""``twin bench``: physics steps per second, bare and in closed loop.

Measured in one process and one call: bare ``mj_step`` on the cncmt axis at a 0.1 ms step
(``mj_step(nstep=N)``, physics only), then the same model closed by the 4th-order H-infinity
controller of seed 000 eq. (28) at 10 kHz (one physics step per control tick) through the
general runner, with recording off, and again with a Rerun recording written.  The runner
picks its compiled loop (:mod:`twin.compiled_loop`) because the controller is a linear
block, as it does for every scenario with linear controllers and no per-step hooks.
"""

from __future__ import annotations

import tempfile
import time
from pathlib import Path

import mujoco

from controllers import make_controller
from twin.machines import build
from twin.recording import record
from twin.references import Step
from twin.sim.runner import simulate

DT = 1e-4


def _closed_loop(machine, seconds: float):
    ctrl = make_controller("seed000_hinf", DT)
    t0 = time.perf_counter()
    result = simulate(machine, [ctrl], Step(0.01), seconds, DT, progress=False)
    return result, time.perf_counter() - t0


def run_bench(seconds: float = 2.0) -> dict:
    """Measure and return the figures (steps/s and their ratios)."""
    machine = build("cncmt", timestep_s=DT)
    n = int(round(seconds / DT))
    data = mujoco.MjData(machine.model)
    data.ctrl[:] = 0.1
    mujoco.mj_step(machine.model, data, nstep=100)  # warm-up
    t0 = time.perf_counter()
    mujoco.mj_step(machine.model, data, nstep=n)
    raw = n / (time.perf_counter() - t0)
    _closed_loop(machine, 0.01)  # warm-up: JIT of the controller kernel
    _, wall = _closed_loop(machine, seconds)
    closed = n / wall
    result, wall_rec = _closed_loop(machine, seconds)
    with tempfile.TemporaryDirectory() as tmp:
        t0 = time.perf_counter()
        record(result, Path(tmp) / "bench.rrd")
        wall_rec += time.perf_counter() - t0
    return {
        "machine": "cncmt",
        "timestep_s": DT,
        "control_rate_hz": 1.0 / DT,
        "controller": "seed000_hinf (eq. 28, 4th order)",
        "simulated_s": seconds,
        "raw_steps_per_s": raw,
        "closed_loop_steps_per_s": closed,
        "ratio": closed / raw,
        "realtime_factor": closed * DT,
        "recording_steps_per_s": n / wall_rec,
        "loop": result.info["loop"],
    }
