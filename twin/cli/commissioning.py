"""The commissioning commands: ``twin frf | lobes | calibrate | excite | tune``."""

from __future__ import annotations

from pathlib import Path

import typer

from twin.cli.common import _check_folder, _check_output, _echo_json, _guard, _parse_sets
from twin.cli.printing import _print_chatter_check
from twin.errors import TwinInputError


def _gain_margin(loop: dict) -> str:
    """A loop's gain margin for the text report: dB at its phase crossover, or infinite."""
    if loop["gain_margin_db"] is None:
        return "infinite"
    return f"{loop['gain_margin_db']:.1f} dB at {loop['gain_margin_hz']:.0f} Hz"


def _timestep_and_sets(sets: list[str], option: str = "--set timestep_s") -> tuple[float | None, dict[str, float]]:
    """``--set`` items as the physics step (``timestep_s=S``, None where not given, within the
    scenario's bounds) and the parameter overrides (the others)."""
    from twin.scenario import MAX_TIMESTEP_S, MIN_TIMESTEP_S

    overrides = _parse_sets(sets)
    timestep = overrides.pop("timestep_s", None)
    if timestep is not None and not (MIN_TIMESTEP_S <= timestep <= MAX_TIMESTEP_S):
        raise TwinInputError(option, timestep, f"must be in [{MIN_TIMESTEP_S:g}, {MAX_TIMESTEP_S:g}] s")
    return timestep, overrides


@_guard
def frf(
    *,
    machine: str = typer.Argument(..., help="A machine (twin list) or a machine file (FILE.toml)"),
    axis: str = typer.Option("x", "--axis", help="The axis to excite"),
    loop: str = typer.Option("velocity", "--loop", help="open | velocity | position"),
    sensor: str = typer.Option("table", "--sensor", help="motor | table: whose position is measured"),
    feedback: str = typer.Option("motor", "--feedback", help="motor | table: the encoder the loop closes on"),
    excitation: str = typer.Option("prbs", "--excitation", help="prbs | chirp | multisine"),
    amplitude: float = typer.Option(1.0, "--amplitude", help="Excitation amplitude, V (peak)"),
    duration: float = typer.Option(16.0, "--duration", help="Recorded time, s"),
    f_max: float = typer.Option(1000.0, "--f-max", help="Highest frequency, Hz"),
    position: float = typer.Option(
        None, "--position", help="The nut's distance from the drive end, m (a machine file with screw_root_diameter_m)"
    ),
    sets: list[str] = typer.Option(None, "--set", help="Parameter override SYMBOL=VALUE"),
    as_json: bool = typer.Option(False, "--json", help="Print the FRF as JSON"),
    plots: Path = typer.Option(None, "--plots", help="Write the Bode plot (PNG) to this folder"),
    rrd: Path = typer.Option(None, "--rrd", help="Write the experiment as a Rerun recording (.rrd)"),
):
    """Measure an axis's frequency response on the twin as a commissioning tool does (excite,
    H1 with coherence, resonances and anti-resonances) beside the model's."""
    from twin import api
    from twin.commissioning.frf import MODE_MIN_COHERENCE, nut_stiffness

    _check_output("--rrd", rrd, ".rrd")
    _check_folder(plots)
    overrides = _parse_sets(sets or [])
    if position is not None:
        if nut_stiffness(machine, axis) is None:
            raise TwinInputError(
                "--position",
                position,
                f"needs screw_root_diameter_m on axis {axis} of a machine file (the stiffness it computes from the "
                "nut's position)",
            )
        overrides[f"{axis}_nut_position_m"] = position
    measured = api.frf(
        machine,
        overrides,
        axis=axis,
        loop=loop,
        sensor=sensor,
        excitation=excitation,
        amplitude_V=amplitude,
        duration_s=duration,
        f_max_hz=f_max,
        feedback=feedback,
    )
    if as_json:
        _echo_json(measured.summary, 1)
    else:
        m = measured.measurement
        typer.echo(
            f"{machine}: axis {axis}, {loop} loop on the {feedback} encoder, {sensor} sensor, "
            f"{excitation} {amplitude:g} V, "
            f"{len(m.frequency_hz)} lines {m.frequency_hz[0]:.2f}-{m.frequency_hz[-1]:.0f} Hz"
        )
        nut = measured.nut_stiffness
        if position is not None and nut is not None:
            typer.echo(
                f"  nut at {position:g} m: axial stiffness {nut['axial_N_per_m'] / 1e6:.4g} N/um, "
                f"torsion {nut['torsion_N_m_per_rad']:.4g} N m/rad"
            )
        doubtful = {(q.kind, q.frequency_hz) for q in m.modes if q.unreliable is not None}
        for label, kind, found, model in (
            ("resonances", "resonance", m.resonances_hz, m.model_resonances_hz),
            ("anti-resonances", "antiresonance", m.antiresonances_hz, m.model_antiresonances_hz),
        ):
            listed = ", ".join(f"{f:.1f}" + (" (unreliable)" if (kind, f) in doubtful else "") for f in found)
            modelled = ", ".join(f"{f:.1f}" for f in model)
            typer.echo(f"  {label} (Hz): {listed or 'none'}   model: {modelled or 'none'}")
        for q in m.modes:
            if q.unreliable is not None:
                kind = "anti-resonance" if q.kind == "antiresonance" else q.kind
                typer.echo(f"  unreliable {kind} {q.frequency_hz:.1f} Hz: {q.unreliable}")
        if m.incoherent_bands_hz:
            bands = ", ".join(f"{lo:.1f}" if lo == hi else f"{lo:.1f}-{hi:.1f}" for lo, hi in m.incoherent_bands_hz)
            typer.echo(f"  coherence < {MODE_MIN_COHERENCE:g} (a mode there is unreliable or missing) at {bands} Hz")
        error = m.max_model_error_db
        typer.echo(
            f"  coherence >= 0.9 on {100 * m.coherent_share:.0f} % of the lines; "
            f"largest |measured - model| there: {'-' if error is None else f'{error:.2f}'} dB"
        )
    if plots is not None:
        plots.mkdir(parents=True, exist_ok=True)
        path = measured.write_bode(plots / f"frf_{Path(machine).stem}_{axis}_{loop}_{sensor}.png")
        typer.echo(f"plot written to {path}", err=as_json)
    if rrd is not None:
        measured.record(rrd)
        typer.echo(f"recording written to {rrd} (view with: rerun {rrd})", err=as_json)


def _parse_rpm(text: str | None) -> tuple[float, float, int] | None:
    """``--rpm MIN:MAX:N`` as (low, high, count).

    Raises
    ------
    TwinInputError
        Not three fields, or not numbers.
    """
    if text is None:
        return None
    parts = text.split(":")
    try:
        if len(parts) != 3:
            raise ValueError
        return float(parts[0]), float(parts[1]), int(parts[2])
    except ValueError:
        raise TwinInputError("--rpm", text, "give MIN:MAX:N, e.g. 5000:25000:200") from None


@_guard
def lobes(
    *,
    scenario: str = typer.Argument(..., help="Scenario TOML file, or a bundled scenario name"),
    method: str = typer.Option("both", "--method", help="zoa | sd | both"),
    rpm: str = typer.Option(None, "--rpm", help="Spindle speeds MIN:MAX:N (default: from the scenario's)"),
    depth_max: float = typer.Option(None, "--depth-max", help="Deepest depth the semi-discretization scans, mm"),
    immersion: float = typer.Option(None, "--immersion", help="Radial immersion a_e/D in (0, 1] (default: a slot)"),
    down: bool = typer.Option(None, "--down/--up", help="Down (climb) or up (conventional) milling"),
    tool: int = typer.Option(None, "--tool", help="The tools entry of this T number"),
    feed_per_tooth: float = typer.Option(0.1, "--feed-per-tooth", help="Chip of a Kienzle material, mm"),
    sets: list[str] = typer.Option(None, "--set", help="Change a field: PATH=VALUE"),
    as_json: bool = typer.Option(False, "--json", help="Print the lobes as JSON"),
    plots: Path = typer.Option(None, "--plots", help="Write the lobes (PNG) to this folder"),
):
    """Stability lobes of the scenario's tool (its dynamics table): the critical axial depth
    against spindle speed by the zero-order solution and semi-discretization, and with a stock
    and a program every cutting line checked against them."""
    from twin import api
    from twin.settings import parse_settings

    _check_folder(plots)
    mode = None if down is None else ("down" if down else "up")
    found = api.lobes(
        scenario,
        method=method,
        rpm=_parse_rpm(rpm),
        depth_max_mm=depth_max,
        immersion=immersion,
        mode=mode,
        tool_number=tool,
        feed_per_tooth_mm=feed_per_tooth,
        **parse_settings(sets or []),
    )
    summary = found.summary
    if as_json:
        _echo_json(summary, 1)
    else:
        typer.echo(
            f"{summary['scenario']}: {summary['tool']}, {summary['n_flutes']} flutes, D {summary['diameter_mm']:g} mm, "
            f"{summary['material']} (K_t {summary['K_t_N_per_mm2']:g} N/mm^2, K_r {summary['K_r']:.3g}), "
            f"a_e/D {summary['immersion']:g} {summary['mode']} milling, {summary['dynamics']}"
        )
        for name, low in summary["lowest"].items():
            rows = summary["lobes"][name]
            span = f"{rows[0]['spindle_rpm']:g}-{rows[-1]['spindle_rpm']:g} rpm ({len(rows)} speeds)"
            where = (
                "no boundary"
                if low is None
                else (f"lowest critical depth {low['critical_depth_mm']:.3f} mm at {low['spindle_rpm']:.0f} rpm")
            )
            typer.echo(f"  {name}: {where} over {span}, {summary['seconds'][name]:.2f} s")
        _print_chatter_check(found.stability_checks)
    if plots is not None:
        plots.mkdir(parents=True, exist_ok=True)
        path = found.write_png(plots / f"lobes_{Path(scenario).stem}.png")
        typer.echo(f"plot written to {path}", err=as_json)


@_guard
def calibrate(
    *,
    machine: str = typer.Argument(..., help="A machine (twin list) or a machine file (FILE.toml)"),
    trace: Path = typer.Option(..., "--trace", help="Measured time trace or FRF, .csv or .parquet"),
    fit: str = typer.Option(..., "--fit", help="Parameters to fit, SYM,SYM"),
    axis: str = typer.Option("x", "--axis", help="The axis an FRF was measured on"),
    sensor: str = typer.Option("table", "--sensor", help="motor | table: where an FRF was measured"),
    sets: list[str] = typer.Option(
        None,
        "--set",
        help="Parameter override SYMBOL=VALUE before the fit; timestep_s=S: the physics step of the fit's twin runs",
    ),
    as_json: bool = typer.Option(False, "--json", help="Print the result as JSON"),
    out: Path = typer.Option(None, "--out", help="Write the calibrated machine file (.toml; machine files only)"),
):
    """Fit named machine parameters to a measured time trace or FRF (least squares through the
    twin), with standard errors and the fit index before and after."""
    from twin import api
    from twin.machines import get_machine
    from twin.results import check_calibrated_output

    _check_output("--out", out, ".toml")
    if out is not None:  # before the fit's minutes
        check_calibrated_output(machine, "--out", out)
    symbols = [s.strip() for s in fit.split(",") if s.strip()]
    timestep, overrides = _timestep_and_sets(sets or [])
    calibration = api.calibrate(
        machine,
        trace,
        symbols,
        overrides=overrides,
        axis=axis,
        sensor=sensor,
        progress=not as_json,
        timestep_s=timestep,
    )
    if as_json:
        _echo_json(calibration.summary, 2)
    else:
        report = calibration.report
        what = "twin runs" if report.kind == "time" else "model evaluations"
        typer.echo(f"{machine}: {report.kind} trace {trace}, {report.evaluations} {what}")
        solver = report.solver
        typer.echo(
            f"  {'converged' if solver.converged else 'NOT converged'}: {solver.termination} "
            f"(optimality {solver.optimality:.2g}"
            + (f", {solver.rejected_diverged} diverging trials rejected)" if solver.rejected_diverged else ")")
        )
        for s, v in report.fitted.items():
            unit = get_machine(machine).parameters[s].unit
            error = report.standard_errors.get(s)
            spread = f" +- {error:.2g}" if error is not None else " (no standard error: the fit did not converge)"
            if s in report.model_errors:
                spread += f" (noise {report.statistical_errors[s]:.2g}, model {report.model_errors[s]:.2g})"
            typer.echo(f"  {s} = {v:.6g} {unit}{spread} (nominal {report.nominal[s]:.6g})")
        for s, why in report.unidentifiable.items():
            typer.echo(f"  {s}: not identifiable, kept at {report.nominal[s]:.6g}: {why}")
        for s, why in report.poorly_determined.items():
            typer.echo(f"  {s}: poorly determined: {why}")
        typer.echo("  fit index: " + ", ".join(f"{k} {v:.2f} %" for k, v in report.fit_index_pct.to_json().items()))
        noise = solver.against_noise
        if noise is not None:
            typer.echo(
                f"  residual {noise.residual_rms_m:.3g} m RMS, the trace's noise {noise.noise_floor_m:.3g} m: "
                + noise.note
            )
        for s, why in report.not_excited.items():
            typer.echo(f"  {s}: not excited: {why}")
    if out is not None:
        calibration.write_machine_file(out)
        typer.echo(f"calibrated machine file written to {out}", err=as_json)


@_guard
def excite(
    *,
    machine: str = typer.Argument(..., help="A machine (twin list) or a machine file (FILE.toml)"),
    out: Path = typer.Option(..., "--out", help="The trace to write, .csv or .parquet"),
    axis: str = typer.Option("x", "--axis", help="The axis to excite"),
    f_max: float = typer.Option(500.0, "--f-max", help="Highest frequency excited, Hz (1.5 x the highest mode)"),
    amplitude: float = typer.Option(2.0, "--amplitude", help="PRBS amplitude, V"),
    duration: float = typer.Option(0.6, "--duration", help="Length, s (an open loop drifts: keep it short)"),
    seed: int = typer.Option(1, "--seed", help="Random seed of the PRBS"),
    simulate: bool = typer.Option(False, "--simulate", help="Add the twin's open-loop response (pos_<axis>_m)"),
    sets: list[str] = typer.Option(None, "--set", help="Parameter override SYMBOL=VALUE (with --simulate)"),
):
    """Write an open-loop PRBS for calibration (time_s, u_<axis>_V at 0.1 ms): play it on the
    machine, add the measured pos_<axis>_m and give it to twin calibrate --trace; --simulate adds
    the twin's own response instead."""
    from twin.commissioning.calibration import excitation_trace, write_table

    if out.suffix not in (".csv", ".parquet"):
        raise TwinInputError("--out", str(out), "must be a .csv or .parquet file")
    _check_output("--out", out)
    columns = excitation_trace(
        machine, axis, f_max, amplitude, duration, seed, _parse_sets(sets or []), simulate_twin=simulate
    )
    write_table(columns, out)
    typer.echo(
        f"{out}: {len(columns['time_s'])} samples, PRBS of {amplitude:g} V on {axis} to about {f_max:g} Hz"
        + (", with the twin's response" if simulate else f": record pos_{axis}_m beside it")
    )


@_guard
def tune(
    *,
    machine: str = typer.Argument(..., help="A machine (twin list) or a machine file (FILE.toml)"),
    sets: list[str] = typer.Option(None, "--set", help="Parameter override SYMBOL=VALUE"),
    control_period: float = typer.Option(None, "--control-period", help="Control period, s (default about 0.1 ms)"),
    feedback: str = typer.Option(
        None,
        "--feedback",
        help="dual | table | motor: velocity on the motor and position on the table's scale, both on the "
        "scale, or both on the motor (default: the machine's, dual for a machine file)",
    ),
    as_json: bool = typer.Option(False, "--json", help="Print the design as JSON"),
    out: Path = typer.Option(None, "--out", help="Write the tuned cascade as a scenario (.toml, a 10 mm circle)"),
    check: bool = typer.Option(True, "--verify/--no-verify", help="Run a step and a circle on the twin"),
    check_margins: bool = typer.Option(
        False,
        "--verify-margins",
        help="Bisect each gain's stability boundary on the twin (as run, without Coulomb friction, linear at the "
        "machine's physics step and a quarter of it) and print it beside the cascade margin",
    ),
):
    """Design each axis's position P / velocity PI cascade with feedforward and a notch or
    low-pass where a resonance needs it (phase margin >= 45 deg, gain margin >= 6 dB on the
    sampled loop with its delay), verify it on the twin and write it as a scenario."""
    from twin import api

    _check_output("--out", out, ".toml")
    if control_period is not None and not (1e-6 <= control_period <= 0.1):
        raise TwinInputError("--control-period", control_period, "must be in [1e-6, 0.1] s")
    tuned = api.tune(machine, _parse_sets(sets or []), control_period, feedback)
    if check:
        tuned.verify()
    if check_margins:
        tuned.verify_margins()
    result = tuned.summary
    if as_json:
        _echo_json(result, 2)
    else:
        typer.echo(f"{machine}: control period {1e3 * result['control_period_s']:g} ms, {result['feedback']} feedback")
        for a, r in result["axes"].items():
            g = r["gains"]
            filt = (
                f"notch {g['notch_hz']:.1f} Hz"
                if g["notch_hz"]
                else (f"low-pass {g['lowpass_hz']:.0f} Hz" if g["lowpass_hz"] else "no filter")
            )
            typer.echo(
                f"  {a}: kp {g['kp_pos']:.4g} 1/s, kv {g['kp_vel']:.4g} V s/m, "
                f"Ti {1e3 * g['ti_vel_s']:.3g} ms, {filt}; "
                f"velocity loop {r['velocity_loop']['crossover_hz']:.1f} Hz, "
                f"position bandwidth {r['bandwidth_hz']:.1f} Hz, "
                f"PM {r['phase_margin_deg']:.1f} deg, "
                f"GM {_gain_margin(r['velocity_loop'])} (velocity loop), {_gain_margin(r['position_loop'])} (position)"
            )
            cascade = r["cascade_margins"]
            typer.echo(
                "     whole cascade, the gain increase to instability: "
                + ", ".join(f"{k} {_gain_margin(cascade[k])}" for k in ("kp_pos", "kp_vel", "ki_vel"))
            )
        for a, v in result.get("verification", {}).items():
            typer.echo(f"  verified on the twin, {a}: " + ", ".join(f"{k} {x:.4g}" for k, x in v.items()))
        if check_margins:
            from twin.commissioning.boundary import CONDITIONS

            typer.echo(
                "  the twin's bisected boundary, dB (less the cascade margin): "
                + ", ".join(CONDITIONS)
                + ", zero step (the linear boundary extrapolated to a zero physics step)"
            )
            for row in tuned.margin_check:
                typer.echo(f"  {row.report_line()}")
    if out is not None:
        out.write_text(tuned.scenario_text(), encoding="utf-8")
        typer.echo(f"scenario written to {out} (run it: twin run {out})", err=as_json)
