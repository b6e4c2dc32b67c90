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

The virtual part (``part``): per case, a whole closed-loop run of a bundled program with a stock
and then its virtual part (walls, height maps, inspection), alternating, at most
:data:`PART_REPEATS` times: the medians of each wall time (``run_s``, ``part_s``) and of the
per-repeat ratio part/run (``part_over_run``), and tracemalloc's peak while the part is
computed (``part_peak_mb``).  Cases: ``gcode_slot_passes`` (four passes, a through-cut), its
first two passes, its through-cut alone, its 0.05 s start with a 100 mm cutter, and the bundled
pocket and test piece.  ``finish``: a generated ball finishing program of ``finish_lines``
lines (:func:`finish_figures`).

Start-up (``startup``): wall time of ``twin run choi1999_cutting_circle --json`` (2.2 s simulated)
as a new Python process (``python -m twin.cli``, as the ``twin`` script), alternating with the
same scenario run in this process after a warm-up (built and simulated: what the run itself
costs); ``overhead_s`` is the median of the per-repeat differences, what a user waits for
imports, the numba cache and writing the summary.  Also ``twin --help`` as a new process.
"""

from __future__ import annotations

import math
import statistics
import subprocess
import sys
import time
from collections.abc import Iterator
from typing import Any

import numpy as np

from controllers import make_controller
from controllers.blocks import with_correction
from controllers.registry import Context, make_observers
from twin.bench_worker import time_case
from twin.machines import build
from twin.outcome import RunOutcome, finish
from twin.references import Step, SumOfSines
from twin.scenario import assemble, load_scenario, run_scenario
from twin.sim.runner import simulate

#: Gains of case (b): P position loop (1/s), PI velocity loop (V s/m, V/m), observer (Hz, order).
CASCADE = {"kp_pos": 200.0, "kp_vel": 7.0, "ki_vel": 400.0}
OBSERVER = {"cutoff_hz": 20.0, "order": 2}
#: Alternating repeats of the virtual part's cases by default (each runs a whole program).
PART_REPEATS = 3
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
    from twin.machining.engagement import StockSpec, ToolSpec
    from twin.machining.program_cut import program_milling

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


def finish_program(n_lines: int, side_mm: float = 100.0) -> Iterator[str]:
    """A 3-D finishing program of about ``n_lines`` lines: a 6 mm ball end mill (T1) over the
    surface ``z = -3 + 1.5 sin(x / 8 mm) cos(y / 8 mm)`` of a ``side_mm`` square, in rows along X
    (alternating) of G1 XYZ moves, as CAM writes a ball finishing pass (four decimals)."""
    rows = max(2, round(math.sqrt(n_lines)))
    per_row = max(2, n_lines // rows)
    yield "%"
    yield "(generated for twin bench: a ball finishing pass over a sine surface)"
    yield "G21 G90 G17 G94 G40 G49 G80"
    yield "G64 P0.01"
    yield "T1 M6"
    yield "S12000 M3"
    xs = np.linspace(0.0, side_mm, per_row)
    for row, y in enumerate(np.linspace(0.0, side_mm, rows)):
        z = -3.0 + 1.5 * np.sin(xs / 8.0) * math.cos(y / 8.0)
        order = range(per_row) if row % 2 == 0 else range(per_row - 1, -1, -1)
        if row == 0:
            yield f"G0 X{xs[0]:.4f} Y{y:.4f} Z1.0000"
            yield f"G1 Z{z[0]:.4f} F600"
            yield "F3000"
        else:
            yield f"G1 Y{y:.4f}"
        for k in order:
            yield f"G1 X{xs[k]:.4f} Z{z[k]:.4f}"
    yield "G0 Z5"
    yield "M30"
    yield "%"


def _run_and_part(scenario) -> tuple[float, float, RunOutcome]:
    """One closed-loop run of a scenario with a stock and then its virtual part: the two wall
    times (s) and the run's outcome (its part computed)."""
    inputs = assemble(scenario)
    t0 = time.perf_counter()
    result = inputs.simulate(progress=False)
    run_s = time.perf_counter() - t0
    t0 = time.perf_counter()
    outcome = finish(result, inputs.program)
    return run_s, time.perf_counter() - t0, outcome


def _part_peak_mb(scenario) -> float:
    """tracemalloc's peak while a run's virtual part is computed, less what the run holds (MB)."""
    import tracemalloc

    inputs = assemble(scenario)
    result = inputs.simulate(progress=False)
    tracemalloc.start()
    finish(result, inputs.program)
    peak = tracemalloc.get_traced_memory()[1] / 1e6
    tracemalloc.stop()
    return peak


def slot_variants(lines: list[str]) -> dict[str, list[str]]:
    """The bundled ``slot_passes.ngc`` (``lines``) cut down to its first two passes, and to its
    pass through the block alone."""
    passes = [i for i, text in enumerate(lines) if text == "G1 X120 F1200"]
    head = lines[: lines.index("G1 Z-2 F600")]  # set-up, spindle, over the start at Z1
    end = ["G0 Z5", "M5", "M30", "%"]
    return {
        "slot_two_passes": [*lines[: passes[1] + 1], *end],
        "slot_through_cut": [*head, "G1 Z-22 F600", "G1 X120 F1200", *end],
    }


def part_figures(repeats: int = 3, finish_lines: int = 17_000) -> dict:
    """The virtual part's cost beside its run's (see the module docstring): per case the run's
    and the part's wall time (medians of alternating repeats), their ratio and the part's peak
    memory (tracemalloc); and a generated ball finishing program's planning, engagement and part
    (:func:`finish_program`)."""
    import tempfile
    from pathlib import Path

    from twin.scenario.files import bundled_scenarios

    out: dict[str, Any] = {"cases": {}}
    with tempfile.TemporaryDirectory() as folder:
        slot = load_scenario("gcode_slot_passes")
        cases = {"slot_four_passes": slot}
        program = bundled_scenarios()["gcode_slot_passes"].parent / "programs" / "slot_passes.ngc"
        for name, text in slot_variants(program.read_text().splitlines()).items():
            path = Path(folder) / f"{name}.ngc"
            path.write_text("\n".join(text) + "\n")
            cases[name] = load_scenario("gcode_slot_passes", {"reference.file": str(path), "inspect": []})
        cases["slot_100mm_cutter_0.05s"] = load_scenario(
            "gcode_slot_passes", {"tools.0.diameter_mm": 100.0, "duration_s": 0.05, "inspect": []}
        )
        cases["pocket_ball_finish"] = load_scenario("gcode_pocket_ball_finish")
        cases["test_piece"] = load_scenario("gcode_test_piece")
        for name, scenario in cases.items():
            _run_and_part(scenario)  # warm-up: compiled kernels loaded
            runs, parts = [], []
            for _ in range(repeats):
                run_s, part_s, outcome = _run_and_part(scenario)
                runs.append(run_s)
                parts.append(part_s)
            out["cases"][name] = {
                "ticks": len(outcome.run.t_s),
                "run_s": statistics.median(runs),
                "part_s": statistics.median(parts),
                "part_over_run": statistics.median(p / r for p, r in zip(parts, runs)),
                "part_peak_mb": _part_peak_mb(scenario),
                "wall_points": len(outcome.part.walls) if outcome.part is not None else 0,
            }
    out["finish"] = finish_figures(finish_lines)
    return out


def finish_figures(lines: int) -> dict:
    """A generated ball finishing program (:func:`finish_program`) of ``lines`` lines: its
    planning and engagement time and their peak memory, then its virtual part's time and peak
    (tracemalloc, beyond what the plan holds) against a stand-in for a run's actual path: the plan
    with seeded 1 µm noise in XY (a run of it is not part of the bench)."""
    import tempfile
    import tracemalloc
    from pathlib import Path

    from twin.gcode.planner import PlannerSettings, plan
    from twin.gcode.reader import read_program
    from twin.machining.engagement import StockSpec, ToolSpec
    from twin.machining.part import virtual_part
    from twin.machining.program_cut import program_milling
    from twin.machining.sweep import ToolSweep

    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "finish.ngc"
        path.write_text("\n".join(finish_program(lines)) + "\n")
        settings = PlannerSettings()
        limits = settings.limits(build("linear_motor_xy").motion_limits)
        tracemalloc.start()
        t0 = time.perf_counter()
        planned = plan(list(read_program(path)), limits, settings)
        plan_s = time.perf_counter() - t0
        stock = StockSpec(corners_mm=((-5.0, -5.0), (105.0, 105.0)), top_mm=0.0, bottom_mm=-10.0, resolution_mm=0.1)
        ball = ToolSpec(number=1, diameter_mm=6.0, n_flutes=2, corner_radius_mm=3.0)
        t0 = time.perf_counter()
        cut = program_milling(planned, stock, None, [ball], 0)
        engagement_s = time.perf_counter() - t0
        plan_peak = tracemalloc.get_traced_memory()[1] / 1e6
        tracemalloc.reset_peak()
        held = tracemalloc.get_traced_memory()[0] / 1e6
        nominal = ToolSweep.planned(planned, cut)
        # a stand-in for a run's actual path: the plan with seeded 1 µm noise in XY
        noise = np.random.default_rng(0).normal(0.0, 1e-3, nominal.xy_mm.shape)
        actual = ToolSweep(nominal.xy_mm + noise, nominal.tip_mm, nominal.radius_mm, nominal.corner_mm, nominal.line)
        t0 = time.perf_counter()
        part = virtual_part(stock, nominal, actual)
        part_s = time.perf_counter() - t0
        part_peak = tracemalloc.get_traced_memory()[1] / 1e6 - held
        tracemalloc.stop()
    return {
        "lines": lines,
        "samples": len(planned.position),
        "cycle_time_s": planned.cycle_time_s,
        "resolution_mm": stock.resolution_mm,
        "plan_s": plan_s,
        "engagement_s": engagement_s,
        "plan_and_engagement_peak_mb": plan_peak,
        "part_s": part_s,
        "part_peak_mb": part_peak,
        "floor_error_um": part.floor_error_um,
    }


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


def run_bench(
    seconds: float = 2.0,
    *,
    repeats: int = 5,
    gcode_lines: int = 1_000_000,
    gcode_moves: int = 10_000,
    finish_lines: int = 17_000,
    part_repeats: int = PART_REPEATS,
    planning_scale: float = 1.0,
    planning_file: str | None = None,
) -> dict:
    """Measure every case and the start-up; figures as in the module docstring.

    Returns
    -------
    dict
        ``cases.<name>.{raw_steps_per_s, closed_loop_steps_per_s, ratio, realtime_factor, loop,
        timestep_s}``, ``startup.{scenario, run_process_s, run_in_process_s, overhead_s,
        help_process_s}``, ``simulated_s``, ``repeats``, ``gcode``, ``part`` and ``planning``
        (:func:`planning_figures`; None with ``planning_scale`` 0).
    """
    out: dict[str, Any] = {
        "simulated_s": seconds,
        "repeats": repeats,
        "cases": {},
        "startup": startup(repeats),
        "gcode": gcode_figures(gcode_lines, repeats, gcode_moves),
        "part": part_figures(part_repeats, finish_lines) if part_repeats else None,
        "planning": planning_figures(planning_scale, planning_file) if planning_scale else None,
    }
    for name, (bm, run) in _cases().items():
        dt = bm.model.opt.timestep
        run(0.01)  # warm-up: load the compiled loop
        raw, closed, ratios = [], [], []
        for _ in range(repeats):
            timing = time_case(bm.model, run, seconds)
            raw.append(timing.bare_steps_per_s)
            closed.append(timing.closed_loop_steps_per_s)
            ratios.append(timing.closed_loop_steps_per_s / timing.bare_steps_per_s)
        out["cases"][name] = {
            "raw_steps_per_s": statistics.median(raw),
            "closed_loop_steps_per_s": statistics.median(closed),
            "ratio": statistics.median(ratios),
            "realtime_factor": statistics.median(closed) * dt,
            "loop": timing.result.info["loop"],
            "timestep_s": dt,
        }
    return out


#: The issue's slow limits (issue 46): 100 mm/s, 1.5 m/s^2, 1500 m/s^3 on X and Y; 50 mm/s,
#: 1 m/s^2, 1000 m/s^3 on Z.
SLOW_LIMITS = ((0.1, 0.1, 0.05), (1.5, 1.5, 1.0), (1500.0, 1500.0, 1000.0))
#: A program file's extra limits: 30.48 mm/s and 508 mm/s^2 per axis (LinuxCNC's, issue 46's
#: CamBam program), the jerk of ``linear_motor_xy``'s X.
FILE_LIMITS = (0.03048, 0.508)


def zigzag_program(n_lines: int) -> list[str]:
    """``n_lines`` 10 mm moves along X, 0.1 mm apart in Y, at 3000 mm/min under G64 P0.01."""
    return ["G21 G90 G17 G64 P0.01", "G0 X0 Y0", "F3000"] + [
        f"G1 X{10 * (k % 2 == 0)} Y{0.1 * k:.1f}" for k in range(n_lines)
    ]


def planning_figures(scale: float = 1.0, file: str | None = None) -> dict:
    """The planner's CPU time against the motion it plans (the program counted, not held:
    memory bounded by the look-ahead window), on ``linear_motor_xy``'s limits and the issue's
    slow ones, for a CAM-like program (20 000 lines), a ball finishing program (17 000), a
    1 000-turn helical arc and a 20 000-line zigzag, each times ``scale``; and ``file`` (also at
    :data:`FILE_LIMITS`).

    Returns
    -------
    dict
        ``<program>.<limits>.{motion_s, plan_cpu_s, ratio, violations}``.
    """
    from twin.gcode.planned import Limits
    from twin.gcode.planner import PlannerSettings, hold_or_count
    from twin.gcode.reader import Reader

    machine = PlannerSettings().limits(build("linear_motor_xy").motion_limits)
    limit_sets = {"linear_motor_xy": machine, "slow": Limits(*SLOW_LIMITS)}
    turns = max(1, round(1000 * scale))
    programs: dict[str, tuple[Any, dict]] = {
        "cam_like": (lambda: cam_program(max(2, round(20_000 * scale))), limit_sets),
        "ball_finishing": (lambda: finish_program(max(2, round(17_000 * scale))), limit_sets),
        f"arc_{turns}_turns": (
            lambda: ["G21 G90 G17 G0 X1 Y0 Z0", f"G2 X1 Y0 Z-20 I-1 J0 P{turns} F600"],
            limit_sets,
        ),
        "zigzag": (lambda: zigzag_program(max(2, round(20_000 * scale))), limit_sets),
    }
    if file is not None:
        velocity, acceleration = FILE_LIMITS
        own = Limits((velocity,) * 3, (acceleration,) * 3, (machine.jerk_m_per_s3[0],) * 3)
        with open(file, encoding="utf-8", errors="replace") as handle:
            text = handle.read().splitlines()
        programs[file] = (lambda: text, {**limit_sets, "30.48mm_s_508mm_s2": own})
    hold_or_count(Reader(["G21 G0 X0", "G1 X1 F100", "G2 X1 Y0 I1 J0"]).moves(), machine, None, most=0)  # compile
    out: dict[str, dict] = {}
    for name, (lines, limits_by_name) in programs.items():
        out[name] = {}
        for limits_name, limits in limits_by_name.items():
            t0 = time.process_time()
            _held, facts, samples = hold_or_count(Reader(lines()).moves(), limits, None, most=0)
            cpu = time.process_time() - t0
            motion = samples * 1e-3
            out[name][limits_name] = {
                "motion_s": motion,
                "plan_cpu_s": cpu,
                "ratio": motion / cpu if cpu > 0 else math.inf,
                "violations": len(facts.violations),
            }
    return out
