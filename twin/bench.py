"""``twin bench``: physics steps per second, bare and in closed loop, for four controller kinds.

For each case, in one process: bare ``mj_step`` on the case's model at its timestep
(``mj_step(nstep=N)``, physics only, no controller, no force) and the same model in closed loop
through the general runner (:func:`twin.sim.runner.simulate`, recording every tick as ``twin
run`` does), alternating, ``repeats`` times.  Reported: the medians of each figure and the
median of the per-repeat ratios closed/bare (each ratio from two timings taken back to back,
so a busy core shows up in both and not in the ratio).

Cases:

(a) ``hinf_cncmt``: Yadav 2020's eq. (28) H-infinity (4th order) on ``cncmt`` at 10 kHz;
(b) ``cascade_dob_googol``: position P around velocity PI with an inverse-model disturbance
    observer on ``googol_xy`` at 10 kHz (the velocity is the encoder's backward difference);
(c) ``npid_googol``: Anang 2017's nonlinear PID (eqs. 6-8) on ``googol_xy`` at 10 kHz;
(d) ``cutting_circle_linear_motor``: the bundled ``choi1999_cutting_circle`` (mechanistic end
    milling every physics step, PID + feedforward at 2 kHz, 0.1 ms physics);
(e) ``gcode_test_piece_linear_motor``: the bundled ``gcode_test_piece`` (the part program planned
    once, before the timing; its reference sampled by Hermite interpolation every tick).

G-code (``gcode``): the reader's lines per second on a generated CAM-like program of
``gcode_lines`` lines read from a file on one core (``read_lines_per_s``: inches, four decimals,
modal words, arcs in G17, G18 and G19, as the 169 220-line program of issue 30), the planner's
wall time for a generated pocket raster of ``plan_moves`` moves (``gcode_moves``, default 10 000),
lines with tangent arc turnarounds (``plan_s``, median of the repeats, and ``plan_moves_per_s``) on
``linear_motor_xy``'s limits, the engagement along it through a 7 mm wide stock with a 1 mm cutter
(``engagement_s``), the peak memory (tracemalloc) of the planner streaming the raster once and
four times over (``stream_peak_mb``, by reference length in s: what grows is each line's text,
feed, spindle and tool, which the per-line results report), and of a whole run of the bundled
``gcode_choi1999_circle`` scenario on a twelfth of the raster and four times that
(``run_peak_mb``, by cycle time in s: both under the 600 s of motion a run holds whole, so it
grows with them; a longer program is streamed, and the recording keeps at most 100 000 ticks).

Start-up (``startup``): wall time of ``twin run choi1999_cutting_circle --json`` (2.2 s simulated)
as a new Python process (``python -m twin.cli``, as the ``twin`` script), alternating with the
same scenario run in this process after a warm-up (built and simulated: what the run itself
costs); ``overhead_s`` is the median of the per-repeat differences, what a user waits for
imports, the numba cache and writing the summary.  Also ``twin --help`` as a new process.
"""

from __future__ import annotations

import statistics
import subprocess
import sys
import time
from collections.abc import Iterator
from typing import Any

import mujoco

from controllers import make_controller
from controllers.blocks import with_correction
from controllers.registry import Context, make_observers
from twin.machines import build
from twin.references import Step, SumOfSines
from twin.scenario import assemble, load_scenario, run_scenario
from twin.sim.runner import simulate

#: Gains of case (b): P position loop (1/s), PI velocity loop (V s/m, V/m), observer (Hz, order).
CASCADE = {"kp_pos": 200.0, "kp_vel": 7.0, "ki_vel": 400.0}
OBSERVER = {"cutoff_hz": 20.0, "order": 2}
#: Bundled scenario of the start-up measurement.
STARTUP_SCENARIO = "choi1999_cutting_circle"


def _cases() -> dict:
    """name -> (machine, run(seconds) -> RunResult); controllers are built here, outside the
    timed runs, so the timing is the loop's."""
    cncmt = build("cncmt", timestep_s=1e-4)
    hinf = make_controller("yadav2020_hinf", 1e-4)
    googol = build("googol_xy", timestep_s=1e-4)
    sine = SumOfSines((0.01,), (0.5,), n_axes=2, axes=(0,))
    ctx = Context(1e-4, ("x", "y"), plants={a.name: googol.plant[i][i] for i, a in enumerate(googol.axes)})
    cascade_dob = with_correction(
        make_controller("cascade", 1e-4, CASCADE, axes=ctx.axes), make_observers("inverse_model", OBSERVER, ctx)
    )
    npid = make_controller("anang2017_npid", 1e-4, axes=ctx.axes)
    cutting = assemble(load_scenario("choi1999_cutting_circle"))
    part = assemble(load_scenario("gcode_test_piece"))
    return {
        "hinf_cncmt": (cncmt, lambda sec: simulate(cncmt, hinf, Step(0.01), sec, 1e-4, progress=False)),
        "cascade_dob_googol": (googol, lambda sec: simulate(googol, cascade_dob, sine, sec, 1e-4, progress=False)),
        "npid_googol": (googol, lambda sec: simulate(googol, npid, sine, sec, 1e-4, progress=False)),
        "cutting_circle_linear_motor": (cutting.machine, lambda sec: cutting.simulate(duration_s=sec, progress=False)),
        "gcode_test_piece_linear_motor": (part.machine, lambda sec: part.simulate(duration_s=sec, progress=False)),
    }


def raster_program(n_moves: int) -> list[str]:
    """A pocket raster of ``n_moves`` moves: 5 mm lines along X joined by tangent half circles
    of 0.5 mm radius (a CAM-style zig-zag at 3000 mm/min)."""
    lines = ["G21 G90 G17 G94", "G64 P0.01", "G0 X0 Y0 Z1", "M3 S10000", "G1 Z-1 F300", "F3000"]
    y = 0.0
    for k in range(n_moves // 2):
        if k % 2 == 0:
            lines += ["G1 X5", f"G3 X5 Y{y + 1:g} I0 J0.5"]
        else:
            lines += ["G1 X0", f"G2 X0 Y{y + 1:g} I0 J0.5"]
        y += 1.0
    return lines


def cam_program(n_lines: int) -> Iterator[str]:
    """A CAM-like program of ``n_lines`` lines: G20, four decimals, modal motion words, arcs in
    the G17, G18 and G19 planes (their end radius within LinuxCNC's tolerance), comments; the
    words of a block in the order posts write them (X Y Z I J K F)."""
    yield "%"
    yield "(generated for twin bench: CAM-style output)"
    yield "G20 G90 G17 G40 G80 G94 G91.1"
    yield "T1 M6"
    yield "S12000 M3"
    yield "G0 X0.0000 Y0.0000 Z0.2000"
    yield "G1 Z-0.0500 F20.0"
    planes = (("G17", "X", "Y", "I", "J"), ("G18", "Z", "X", "K", "I"), ("G19", "Y", "Z", "J", "K"))
    order = "XYZIJKF"

    def block(code: str, **words: str) -> str:
        return " ".join([code, *(f"{letter}{words[letter]}" for letter in order if letter in words)]).strip()

    n = 7
    while n < n_lines - 2:
        plane, a, b, i, j = planes[(n // 60) % 3]
        step = (n % 97) * 0.0013
        far, back = f"{0.3 - step / 7:.4f}", f"{0.6 + step:.4f}"
        yield block(f"{plane} G1", **{a: f"{0.5 + step:.4f}", b: "0.2500", "F": "40.0"})
        yield block("", **{a: back, b: far})
        yield block("G2", **{a: f"{0.7 + step:.4f}", b: far, i: "0.0500", j: "0.0000"})
        yield block("G3", **{a: back, b: far, i: "-0.0500", j: "0.0000"}) + " (return)"
        n += 4
    yield "M30"
    yield "%"


def gcode_figures(lines: int = 1_000_000, repeats: int = 5, moves: int = 10_000) -> dict:
    """The reader's throughput, the planner's time and the stream's memory (see the module
    docstring)."""
    import tempfile
    import tracemalloc
    from pathlib import Path

    from twin import api
    from twin.gcode.planner import PlannerSettings, plan, plan_stream
    from twin.gcode.reader import Reader, read_program
    from twin.process.machining import StockSpec, ToolSpec, program_milling

    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "cam.ngc"
        with path.open("w") as out:
            for text in cam_program(lines):
                out.write(text + "\n")
        t0 = time.perf_counter()
        read = sum(1 for _ in read_program(path))
        read_s = time.perf_counter() - t0
    settings = PlannerSettings()
    limits = settings.limits(build("linear_motor_xy").motion_limits)
    program = list(Reader(raster_program(moves)).moves())

    timings, engagement = [], []
    stock = StockSpec(corners_mm=((-1.0, -1.0), (6.0, moves / 2 + 2.0)), top_mm=0.0, bottom_mm=-5.0)
    for _ in range(repeats):
        t0 = time.perf_counter()
        planned = plan(program, limits, settings)
        timings.append(time.perf_counter() - t0)
        t0 = time.perf_counter()
        program_milling(planned, stock, ToolSpec(diameter_mm=1.0, n_flutes=2), [], 0)
        engagement.append(time.perf_counter() - t0)
    peaks = {}
    with tempfile.TemporaryDirectory() as folder:
        for times in (1, 4):  # read from a file, as a run streams it (a list of lines is held whole)
            path = Path(folder) / f"raster{times}.ngc"
            path.write_text("\n".join(raster_program(moves * times)) + "\n")
            tracemalloc.start()
            chunks, _facts = plan_stream(read_program(path), limits, settings)
            samples = sum(len(chunk.position) for chunk in chunks)
            peaks[f"{samples / 1e3:.0f}"] = tracemalloc.get_traced_memory()[1] / 1e6
            tracemalloc.stop()
    run_peaks = {}
    with tempfile.TemporaryDirectory() as folder:
        # the bundled circle's scenario (no stock: its reference streamed) on the raster, after a
        # run that loads what a first run loads; then the raster and four times the raster
        for times in (0, 1, 4):
            path = Path(folder) / f"run{times}.ngc"
            path.write_text("\n".join(raster_program(max(2, moves // 12 * times))) + "\n")
            tracemalloc.start()
            run = api.run(api.load("gcode_choi1999_circle", **{"reference.file": str(path)}))
            if times:
                run_peaks[f"{run.summary['cycle_time_s']:.0f}"] = tracemalloc.get_traced_memory()[1] / 1e6
            tracemalloc.stop()
    plan_s = statistics.median(timings)
    return {
        "gcode_lines": lines,
        "moves_read": read,
        "read_lines_per_s": lines / read_s,
        "plan_moves": len(program),
        "plan_s": plan_s,
        "plan_moves_per_s": len(program) / plan_s,
        "plan_cycle_time_s": planned.cycle_time_s,
        "engagement_s": statistics.median(engagement),
        "stream_peak_mb": peaks,
        "run_peak_mb": run_peaks,
    }


def _bare_steps_per_s(model, n: int) -> float:
    data = mujoco.MjData(model)
    data.ctrl[:] = 0.1
    t0 = time.perf_counter()
    mujoco.mj_step(model, data, nstep=n)
    return n / (time.perf_counter() - t0)


def _wall_s(command: list[str]) -> float:
    t0 = time.perf_counter()
    subprocess.run(command, check=True, capture_output=True)
    return time.perf_counter() - t0


def startup(repeats: int = 5) -> dict:
    """Start-up figures of the module docstring (s, medians of ``repeats``)."""
    twin = [sys.executable, "-m", "twin.cli"]
    scenario = load_scenario(STARTUP_SCENARIO)
    run_scenario(scenario, progress=False)  # warm-up: the compiled loop is loaded
    process, in_process, help_ = [], [], []
    for _ in range(repeats):
        process.append(_wall_s([*twin, "run", STARTUP_SCENARIO, "--json"]))
        t0 = time.perf_counter()
        run_scenario(scenario, progress=False)
        in_process.append(time.perf_counter() - t0)
        help_.append(_wall_s([*twin, "--help"]))
    return {
        "scenario": STARTUP_SCENARIO,
        "run_process_s": statistics.median(process),
        "run_in_process_s": statistics.median(in_process),
        "overhead_s": statistics.median(p - i for p, i in zip(process, in_process)),
        "help_process_s": statistics.median(help_),
    }


def run_bench(seconds: float = 2.0, repeats: int = 5, gcode_lines: int = 1_000_000, gcode_moves: int = 10_000) -> dict:
    """Measure every case and the start-up; figures as in the module docstring.

    Returns
    -------
    dict
        ``cases.<name>.{raw_steps_per_s, closed_loop_steps_per_s, ratio, realtime_factor, loop,
        timestep_s}``, ``startup.{scenario, run_process_s, run_in_process_s, overhead_s,
        help_process_s}``, ``simulated_s``, ``repeats``.
    """
    out: dict[str, Any] = {
        "simulated_s": seconds,
        "repeats": repeats,
        "cases": {},
        "startup": startup(repeats),
        "gcode": gcode_figures(gcode_lines, repeats, gcode_moves),
    }
    for name, (bm, run) in _cases().items():
        dt = bm.model.opt.timestep
        n = round(seconds / dt)
        run(0.01)  # warm-up: load the compiled loop
        raw, closed, ratios = [], [], []
        for _ in range(repeats):
            raw.append(_bare_steps_per_s(bm.model, n))
            t0 = time.perf_counter()
            result = run(seconds)
            closed.append(n / (time.perf_counter() - t0))
            ratios.append(closed[-1] / raw[-1])
        out["cases"][name] = {
            "raw_steps_per_s": statistics.median(raw),
            "closed_loop_steps_per_s": statistics.median(closed),
            "ratio": statistics.median(ratios),
            "realtime_factor": statistics.median(closed) * dt,
            "loop": result.info["loop"],
            "timestep_s": dt,
        }
    return out
