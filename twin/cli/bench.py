"""``twin bench``: the loop's, the G-code reader's, the planner's, the part's and the sweep's speed."""

from __future__ import annotations

from pathlib import Path

import typer

from twin.cli.common import _echo_json, _guard
from twin.errors import TwinInputError


@_guard
def bench(
    *,
    as_json: bool = typer.Option(False, "--json", help="Print the figures as JSON"),
    seconds: float = typer.Option(2.0, help="Simulated time per measurement (s)"),
    repeats: int = typer.Option(None, help="Alternating repeats; medians are reported (default 5; --sweep: 1)"),
    sweep: bool = typer.Option(False, "--sweep", help="Benchmark twin sweep instead (twin/sweeps/bench.py)"),
    samples: int = typer.Option(1000, "--samples", help="--sweep: samples of 2 s of the cutting circle"),
    memory_samples: int = typer.Option(
        10_000, "--memory-samples", help="--sweep: one-tick samples for the client memory check"
    ),
    gcode_lines: int = typer.Option(1_000_000, "--gcode-lines", help="Lines of the G-code reader's program"),
    gcode_moves: int = typer.Option(10_000, "--gcode-moves", help="Moves of the planner's and engagement's program"),
    finish_lines: int = typer.Option(
        17_000, "--finish-lines", help="Lines of the generated ball finishing program of the part's figures"
    ),
    part_repeats: int = typer.Option(
        3, "--part-repeats", help="Alternating repeats of the virtual part's cases (0: leave the part out)"
    ),
    planning_only: bool = typer.Option(
        False, "--planning-only", help="Only the planner's speed against the motion it plans"
    ),
    planning_scale: float = typer.Option(
        1.0, "--planning-scale", help="Factor on the planning programs' lengths (lines, turns; 0: leave them out)"
    ),
    planning_file: Path = typer.Option(None, "--planning-file", help="A part program to plan too"),
    against: str = typer.Option(
        None, "--against", help="Time the closed-loop cases of commit REV (A) and this checkout (B) alternately"
    ),
    case: list[str] = typer.Option(None, "--case", help="--against: a case to time (repeat it; default all)"),
):
    """Steps per second, bare mj_step vs the closed loop, for four controller kinds and a part
    program, start-up time, the G-code reader's lines/s and the planner's time (twin/bench.py);
    with --sweep, twin sweep's wall time, samples/s, parallel efficiency and memory; with
    --against REV, the closed-loop cases of REV's tree and this checkout's, alternately, and
    their ratio (twin/bench_against.py)."""
    from twin.bench import run_bench

    if not (seconds > 0 and seconds <= 600):
        raise TwinInputError("--seconds", seconds, "must be in (0, 600]")
    repeats = repeats if repeats is not None else 1 if sweep else 15 if against is not None else 5
    if not 1 <= repeats <= 100:
        raise TwinInputError("--repeats", repeats, "must be in 1..100")
    if not 2 <= gcode_lines <= 10_000_000:
        raise TwinInputError("--gcode-lines", gcode_lines, "must be in 2..10000000")
    if not 2 <= gcode_moves <= 100_000:
        raise TwinInputError("--gcode-moves", gcode_moves, "must be in 2..100000")
    if not 2 <= finish_lines <= 1_000_000:
        raise TwinInputError("--finish-lines", finish_lines, "must be in 2..1000000")
    if not 0 <= part_repeats <= 100:
        raise TwinInputError("--part-repeats", part_repeats, "must be in 0..100")
    if not (planning_scale == 0 or 1e-3 <= planning_scale <= 10.0):
        raise TwinInputError("--planning-scale", planning_scale, "must be 0 (leave planning out) or in [0.001, 10]")
    if planning_file is not None and not planning_file.is_file():
        raise TwinInputError("--planning-file", str(planning_file), "is not a file")
    if case and against is None:
        raise TwinInputError("--case", case[0], "is for --against only")
    if against is not None:
        _bench_against(as_json=as_json, rev=against, cases=case or [], seconds=seconds, repeats=repeats)
        return
    if sweep:
        _bench_sweep(as_json, samples, memory_samples, repeats)
        return
    file = str(planning_file) if planning_file else None
    if planning_only:
        from twin.bench import planning_figures

        planning = planning_figures(planning_scale or 1.0, file)
        if as_json:
            _echo_json({"planning": planning}, 2)
        else:
            _print_planning_bench(planning)
        return
    figures = run_bench(
        seconds,
        repeats=repeats,
        gcode_lines=gcode_lines,
        gcode_moves=gcode_moves,
        finish_lines=finish_lines,
        part_repeats=part_repeats,
        planning_scale=planning_scale,
        planning_file=file,
    )
    if as_json:
        _echo_json(figures, 2)
        return
    typer.echo(f"medians of {repeats} alternating repeats, {seconds:g} s simulated each")
    typer.echo(f"{'case':<30} {'bare steps/s':>14} {'closed steps/s':>15} {'ratio':>6} {'x realtime':>11}  loop")
    for name, f in figures["cases"].items():
        typer.echo(
            f"{name:<30} {f['raw_steps_per_s']:>14,.0f} {f['closed_loop_steps_per_s']:>15,.0f} "
            f"{f['ratio']:>6.3f} {f['realtime_factor']:>11.1f}  {f['loop']}"
        )
    f = figures["startup"]
    typer.echo(
        f"start-up: twin run {f['scenario']} {f['run_process_s']:.2f} s as a new process, "
        f"{f['run_in_process_s']:.2f} s in process, overhead {f['overhead_s']:.2f} s; "
        f"twin --help {f['help_process_s']:.2f} s"
    )
    g = figures["gcode"]
    typer.echo(
        f"G-code: read {g['gcode_lines']:,} CAM-like lines at {g['read_lines_per_s']:,.0f} lines/s; "
        f"planned {g['plan_moves']:,} moves in {g['plan_s']:.2f} s ({g['plan_moves_per_s']:,.0f} moves/s, "
        f"cycle time {g['plan_cycle_time_s']:.0f} s), their engagement in {g['engagement_s']:.2f} s; "
        "the streamed plan's peak memory "
        + ", ".join(f"{mb:.1f} MB for {length} s" for length, mb in g["stream_peak_mb"].items())
        + "; a run's "
        + ", ".join(f"{mb:.1f} MB for {length} s" for length, mb in g["run_peak_mb"].items())
    )
    if figures["part"] is not None:
        _print_part_bench(figures["part"])
    if figures["planning"] is not None:
        _print_planning_bench(figures["planning"])


def _print_planning_bench(planning: dict) -> None:
    """``twin bench``'s planning figures: motion time over the planner's CPU time per program
    and limits (issue 46: at least 100)."""
    typer.echo(f"{'planning':<30} {'limits':<20} {'motion s':>10} {'plan CPU s':>11} {'motion/plan':>12}")
    for name, by_limits in planning.items():
        for limits, f in by_limits.items():
            typer.echo(
                f"{name[-30:]:<30} {limits:<20} {f['motion_s']:>10.1f} {f['plan_cpu_s']:>11.2f} {f['ratio']:>12.0f}"
                + (f"  ({f['violations']} over a limit)" if f["violations"] else "")
            )
    typer.echo("target (issue 46): motion/plan >= 100 at any limits")


def _print_part_bench(part: dict) -> None:
    """``twin bench``'s virtual part figures: each case's run beside its part, and the finishing
    program's."""
    typer.echo(f"{'virtual part':<30} {'ticks':>8} {'run s':>8} {'part s':>8} {'part/run':>9} {'part peak MB':>13}")
    for name, f in part["cases"].items():
        typer.echo(
            f"{name:<30} {f['ticks']:>8,} {f['run_s']:>8.2f} {f['part_s']:>8.2f} "
            f"{f['part_over_run']:>9.2f} {f['part_peak_mb']:>13.1f}"
        )
    typer.echo("targets (issue 45): part/run <= 1, part peak < 1000 MB, slot_four_passes part < 10 s")
    f = part["finish"]
    typer.echo(
        f"ball finishing program: {f['lines']:,} lines, {f['samples']:,} samples ({f['cycle_time_s']:.0f} s of motion) "
        f"at {f['resolution_mm']:g} mm cells: planned in {f['plan_s']:.1f} s, engagement {f['engagement_s']:.1f} s "
        f"(peak {f['plan_and_engagement_peak_mb']:.0f} MB), part {f['part_s']:.1f} s (peak {f['part_peak_mb']:.0f} MB)"
    )


def _bench_against(*, as_json: bool, rev: str, cases: list[str], seconds: float, repeats: int) -> None:
    """``twin bench --against REV``: each case's closed-loop steps/s in REV's tree (A) and this
    checkout (B), timed alternately, and the median ratio B/A."""
    from twin.bench_against import compare

    f = compare(rev, cases, seconds, repeats)
    if as_json:
        _echo_json(f, 2)
        return
    edited = " with uncommitted edits" if f["b_modified"] else ""
    typer.echo(
        f"A = {rev} ({f['a_commit'][:10]}), B = this checkout ({f['b_commit'][:10]}{edited}); "
        f"medians of {repeats} alternating pairs, {seconds:g} s simulated each"
    )
    typer.echo(
        f"{'case':<30} {'A steps/s':>11} {'B steps/s':>11} {'B/A':>6} {'B/A CPU':>8} "
        f"{'A closed/bare':>14} {'B closed/bare':>14}"
    )
    for name, c in f["cases"].items():
        typer.echo(
            f"{name:<30} {c['a']['closed_loop_steps_per_s']:>11,.0f} {c['b']['closed_loop_steps_per_s']:>11,.0f} "
            f"{c['b_over_a']:>6.3f} {c['b_over_a_cpu']:>8.3f} {c['a']['ratio']:>14.3f} {c['b']['ratio']:>14.3f}"
        )
    for tree in ("a", "b"):
        if f[f"only_in_{tree}"]:
            typer.echo(f"only in {tree.upper()} (not timed): {', '.join(f[f'only_in_{tree}'])}")


def _bench_sweep(as_json: bool, samples: int, memory_samples: int, repeats: int) -> None:
    from twin.sweeps.bench import run_sweep_bench

    for option, value in (("--samples", samples), ("--memory-samples", memory_samples)):
        if not 1 <= value <= 100_000:
            raise TwinInputError(option, value, "must be in 1..100000")
    f = run_sweep_bench(samples=samples, repeats=repeats, memory_samples=memory_samples, progress=not as_json)
    if as_json:
        _echo_json({"sweep": f}, 2)
        return
    typer.echo(
        f"twin sweep {f['scenario']} ({', '.join(f['settings'])}) --vary {' --vary '.join(f['vary'])}, "
        f"{f['samples']} samples, median of {f['repeats']}:"
    )
    typer.echo(
        f"  1 worker {f['wall_s_1_worker']:.1f} s, 2 workers {f['wall_s_2_workers']:.1f} s "
        f"(target <= {f['target_wall_s']:g} s), {f['samples_per_s_2_workers']:.1f} samples/s; parallel "
        f"efficiency {f['parallel_efficiency']:.3f} (target >= {f['target_efficiency']:g})"
    )
    typer.echo(
        f"  client memory grew {f['client_memory_growth_MB']:.1f} MB over {f['memory_samples']} one-tick samples"
    )
    typer.echo(
        f"  a plain loop over twin run processes: {f['twin_run_loop_s_per_sample']:.2f} s per sample "
        f"({f['twin_run_loop_samples']} timed), {f['twin_run_loop_extrapolated_s']:.0f} s for "
        f"{f['samples']} samples"
    )
