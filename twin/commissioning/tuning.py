"""Auto-tuning: the cascade a drive's commissioning tool sets, designed on the sampled loop.

Per axis, from the machine's transfer functions with their delay, drive input V to the
position (m) of the encoder each loop reads (:data:`twin.sim.drive.FEEDBACK`): G_v the
velocity loop's (the motor's in table travel, except ``feedback = "table"``), G_p the position
loop's (the table's, except ``feedback = "motor"``, a semi-closed loop), at the control period T:

1. Velocity loop (velocity from G_v's position by backward difference, as the twin's sensor):
   a PI, kv (1 + 1/(Ti s)), with Ti = 4 / w_c, in series with a filter; for each crossover
   w_c from high to low and each filter (none, a notch at each model resonance above w_c, a
   second-order low-pass at 4 w_c), kv puts |L_v| = 1 at w_c; the first design with a phase
   margin >= 45 deg, a gain margin >= 6 dB and a stable closed loop wins (the highest bandwidth
   the resonances allow).  The margins are every crossing's (the gain crossovers' smallest
   |phase margin|, the -180 deg crossings' smallest |gain margin|:
   :func:`controllers.design.loop_analysis.crossing_margins`), so a resonance that crosses
   again above the crossover counts.
2. Position loop: a P gain kp, from w_c / 4 down, the first with the same margins on
   L_p = kp C_v G_p / (1 + C_v D G_v), and a gain margin >= 6 dB either way for each gain in the
   whole cascade (:func:`cascade_margins`; where that needs kp below half of w_c / 4, a lower
   velocity crossover instead); in a semi-closed loop also with the table's response to the
   reference, L_p / (1 + L_p) G_table / G_motor, peaking at most 3 dB (the drive train's mode
   is outside the loop: closed on the motor alone, a 200 kg table overshot a step by 45 %).
3. Feedforward: the whole reference velocity into the velocity loop, and the drive input the
   rigid body needs, acceleration_ff = 1 / (s^2 coefficient of G_p's gain) (V s^2/m) and
   friction_ff its viscous term (V s/m).

Every loop is evaluated exactly as the twin runs it: G by zero-order hold with the delay in
whole periods, the controller and filter by Tustin, on a frequency grid up to Nyquist.
(:mod:`controllers.design.cascade`, Maharof 2021's procedure, solves for a PI with given margins
exactly; this maximises the bandwidth with margins at least the targets, filter included.)
"""

from __future__ import annotations

import math
from pathlib import Path

import control
import numpy as np

from controllers.design.loop_analysis import CrossingMargins, crossing_margins, phase_crossings
from controllers.kinds.generic import velocity_filter
from controllers.lti import SisoTf
from twin.commissioning.frf import discretized, model_modes, rigid_body, sensor_plant, zoh_response
from twin.errors import TwinInputError
from twin.machines import BuiltMachine, build, get_machine
from twin.metrics import tracking_summary
from twin.scenario import load_scenario, run_scenario
from twin.sim.drive import FEEDBACK

#: Stated targets (sampled loops, with the delay).
PHASE_MARGIN_DEG = 45.0
GAIN_MARGIN_DB = 6.0
#: Largest magnitude of the table's response to the reference in a semi-closed loop (+3 dB).
MAX_TABLE_PEAK = 10 ** (3 / 20)
#: Where the whole cascade's margins need the position gain below this share of its start
#: (a quarter of the velocity crossover), the design takes a lower velocity crossover instead:
#: on mid_size_xy's Y closed on the scale the cascade's margins otherwise left a 5.9 Hz position
#: loop under a 94 Hz velocity loop, with it 42 Hz under 86 Hz.
MIN_POSITION_SHARE = 0.5
#: Control period (s) the design assumes unless told (a multiple of the physics step).
CONTROL_PERIOD_S = 1e-4


def _meets(m: CrossingMargins) -> bool:
    """Whether the margins over every crossing meet the targets (an infinite one does)."""
    return (m.pm_deg is None or abs(m.pm_deg) >= PHASE_MARGIN_DEG) and (
        m.gm_db is None or abs(m.gm_db) >= GAIN_MARGIN_DB
    )


def _cascade_meets(margins: dict) -> bool:
    """Whether each gain may change by :data:`GAIN_MARGIN_DB` either way in the whole cascade
    (:func:`cascade_margins`; a margin that no crossing bounds is infinite)."""
    return all(
        (m["gain_margin_db"] is None or m["gain_margin_db"] >= GAIN_MARGIN_DB)
        and (m["decrease_margin_db"] is None or m["decrease_margin_db"] <= -GAIN_MARGIN_DB)
        for m in margins.values()
    )


def _smaller(a: float | None, b: float | None) -> float | None:
    """Of two margins the one nearer to instability (None: infinite)."""
    return min((m for m in (a, b) if m is not None), key=abs, default=None)


def _stable(loop) -> bool:
    """Whether the unity feedback of ``loop`` (discrete) is stable; a pole at z = 1 within 1e-6
    is the table's integrator that the velocity's difference cancels (not a mode of the loop)."""
    poles = control.poles(control.feedback(loop))
    return bool(np.all((np.abs(poles) < 1.0 - 1e-9) | (np.abs(poles - 1.0) < 1e-6)))


def cascade_margins(
    freqs_hz: np.ndarray,
    kv: float,
    kp: float,
    *,
    f_resp: np.ndarray,
    i_resp: np.ndarray,
    v_resp: np.ndarray,
    p_resp: np.ndarray,
) -> dict:
    """The margins of each tuned gain in the whole cascade, every loop closed (the sampled
    loop with its delay): for the position gain kp, the velocity gain kv and the integral gain
    kv / Ti, the gain margin (dB) of the loop broken at that gain, and its phase crossover
    (Hz), the factor by which the gain alone can change before the cascade goes unstable.

    With the velocity controller kv (1 + I) F (I = 1 / (Ti s), F the filter, both by Tustin) and
    H = D G_v + kp G_p (the velocity's difference of the velocity sensor's plant, and the position
    sensor's), the cascade's characteristic equation 1 + kv (1 + I) F H = 0 is 1 + L = 0 with

        L_kp = kp kv (1 + I) F G_p / (1 + kv (1 + I) F D G_v)     (the position loop)
        L_kv = kv (1 + I) F H
        L_ki = kv I F H / (1 + kv F H)

    each linear in its gain (the velocity loop's own margins, of kv (1 + I) F D G_v, hold for the
    inner loop alone: on heavy_xy's Y 14 dB against the cascade's 9.5).

    Parameters
    ----------
    freqs_hz : ndarray
        The grid (Hz, to Nyquist).
    kv, kp : float
        The velocity (V s/m) and position (1/s) gains.
    f_resp, i_resp : ndarray
        F's and I's frequency responses on the grid (Tustin).
    v_resp, p_resp : ndarray
        D G_v's and G_p's (zero-order hold with the delay; D by backward difference).

    Returns
    -------
    dict
        ``kp_pos``, ``kp_vel``, ``ki_vel``: each ``gain_margin_db`` and ``gain_margin_hz``, the
        increase that makes the cascade unstable and its frequency, and ``decrease_margin_db``
        and ``decrease_margin_hz``, the decrease (negative dB; a conditionally stable loop's);
        None where no crossing bounds it (:func:`controllers.design.loop_analysis.phase_crossings`).
    """
    h = v_resp + kp * p_resp
    loops = {
        "kp_pos": kp * kv * (1 + i_resp) * f_resp * p_resp / (1 + kv * (1 + i_resp) * f_resp * v_resp),
        "kp_vel": kv * (1 + i_resp) * f_resp * h,
        "ki_vel": kv * i_resp * f_resp * h / (1 + kv * f_resp * h),
    }
    out = {}
    for name, loop in loops.items():
        crossings = phase_crossings(freqs_hz, loop)
        up = min((c for c in crossings if c[0] > 0), default=None)
        down = max((c for c in crossings if c[0] < 0), default=None)
        out[name] = {
            "gain_margin_db": None if up is None else round(up[0], 4),
            "gain_margin_hz": None if up is None else round(up[1], 4),
            "decrease_margin_db": None if down is None else round(down[0], 4),
            "decrease_margin_hz": None if down is None else round(down[1], 4),
        }
    return out


def tune_axis(
    bm: BuiltMachine,
    i: int,
    dt: float,
    *,
    resonances_hz: list[float],
    velocity_sensor: str = "table",
    position_sensor: str = "table",
) -> dict:
    """One axis's design (see the module docstring), on the transfer functions to the encoders
    the loops close on (each ``"table"`` or ``"motor"``: :func:`twin.commissioning.frf.sensor_plant`)."""
    delay = round(bm.delay_s / dt)
    z = control.tf([1.0, 0.0], [1.0], dt)

    def sampled(g):
        gd = discretized(g, dt, "zoh")
        return control.ss(control.tf([1.0], [1.0] + [0.0] * delay, dt)) * gd if delay else gd

    g, g_pos = sensor_plant(bm, i, velocity_sensor), sensor_plant(bm, i, position_sensor)
    gd, gd_pos = sampled(g), sampled(g_pos)
    diff = control.ss((z - 1) / (dt * z))
    nyquist = 0.5 / dt
    freqs = np.geomspace(0.1, nyquist, 3000)  # to Nyquist: a sampled loop often crosses there
    zs = np.exp(2j * math.pi * freqs * dt)
    zs[-1] = -1.0
    g_resp = zoh_response(g, dt, bm.delay_s, freqs)
    pos_resp = zoh_response(g_pos, dt, bm.delay_s, freqs)
    # a semi-closed loop moves the table through the drive train: its response to the reference
    # is the loop's times table / motor, whose peak the design bounds
    to_table = zoh_response(bm.plant[i][i], dt, bm.delay_s, freqs) / pos_resp if position_sensor == "motor" else None
    d_resp = (zs - 1) / (dt * zs)
    s_tustin = 2.0 / dt * (zs[:-1] - 1) / (zs[:-1] + 1)  # Nyquist is s = infinity
    for f_c in np.geomspace(0.4 * nyquist, 2.0, 80):
        w = 2 * math.pi * f_c
        ti = 4.0 / w
        filters = [(0.0, 0.0)] + [(fr, 0.0) for fr in resonances_hz if fr > f_c] + [(0.0, min(4 * f_c, 0.45 / dt))]
        for notch, lowpass in filters:
            f = velocity_filter(notch, 20.0, 0.5, lowpass)
            pi = SisoTf((ti, 1.0), (ti, 0.0))  # 1 + 1/(Ti s)
            num, den = np.polymul(pi.num, f.num), np.polymul(pi.den, f.den)
            unit = discretized(SisoTf(num, den), dt, "tustin")
            filter_at_nyquist = discretized(f, dt, "tustin")(-1.0)
            c_resp = np.append(np.polyval(num, s_tustin) / np.polyval(den, s_tustin), complex(unit(-1.0)))
            at = np.exp(2j * math.pi * f_c * dt)
            kv = 1.0 / abs(complex(unit(at)) * complex(gd(at)) * (at - 1) / (dt * at))
            lv = kv * c_resp * g_resp * d_resp
            velocity = crossing_margins(freqs, lv)
            if not _meets(velocity) or not _stable(kv * unit * gd * diff):
                continue
            f_resp = np.append(np.polyval(f.num, s_tustin) / np.polyval(f.den, s_tustin), complex(filter_at_nyquist))
            i_resp = np.append(1.0 / (ti * s_tustin), 0.0)  # Tustin's integrator: 0 at Nyquist
            for kp in w / 4.0 * np.geomspace(1.0, 0.02, 40):
                lp = kp * kv * c_resp * pos_resp / (1 + lv)
                position = crossing_margins(freqs, lp)
                cv = kv * unit
                table_ok = to_table is None or np.abs(lp / (1 + lp) * to_table).max() <= MAX_TABLE_PEAK
                if not (table_ok and _meets(position) and _stable(kp * cv * gd_pos / (1 + cv * diff * gd))):
                    continue
                cascade = cascade_margins(
                    freqs, kv, kp, f_resp=f_resp, i_resp=i_resp, v_resp=g_resp * d_resp, p_resp=pos_resp
                )
                if not _cascade_meets(cascade) and kp < MIN_POSITION_SHARE * w / 4.0:
                    break  # a lower velocity crossover, rather than a position loop far below it
                if _cascade_meets(cascade):
                    closed = np.abs(lp / (1 + lp))
                    below = np.flatnonzero(closed < 10 ** (-3 / 20))
                    worst = CrossingMargins(
                        _smaller(velocity.pm_deg, position.pm_deg), None, _smaller(velocity.gm_db, position.gm_db), None
                    ).as_dict()
                    return {
                        **{k: v for k, v in worst.items() if not k.endswith("_hz")},
                        "bandwidth_hz": float(freqs[below[0]]) if below.size else float(freqs[-1]),
                        "cascade_margins": cascade,
                        "velocity_loop": {"crossover_hz": float(f_c), **velocity.as_dict()},
                        "position_loop": position.as_dict(),
                        "gains": {
                            "kp_pos": float(kp),
                            "kp_vel": float(kv),
                            "ti_vel_s": float(ti),
                            "velocity_ff": 1.0,
                            "acceleration_ff": float(rigid_body(g_pos)[0]),
                            "friction_ff": float(rigid_body(g_pos)[1]),
                            "notch_hz": float(notch),
                            "lowpass_hz": float(lowpass),
                        },
                    }
    raise TwinInputError("machine", bm.name, f"no cascade meets the margins on axis {bm.axes[i].name}")


def tune(
    machine: str,
    overrides: dict[str, float] | None = None,
    control_period_s: float | None = None,
    feedback: str | None = None,
) -> dict:
    """Design every axis's cascade (see the module docstring), its loops closed as ``feedback``
    says (:data:`twin.sim.drive.FEEDBACK`; default: the machine's, dual for a machine file:
    velocity on the motor's encoder, position on the table's scale).

    Returns
    -------
    dict
        ``machine``, ``control_period_s``, ``feedback``, ``targets`` and per axis ``axes.<a>``:
        ``phase_margin_deg``, ``gain_margin_db`` (of the two loops' the nearer to instability;
        None with a ``..._note`` where infinite),
        ``bandwidth_hz`` (the closed position loop's -3 dB), the two loops' figures and ``gains``.
    """
    if feedback is not None and feedback not in FEEDBACK:
        raise TwinInputError("--feedback", feedback, f"must be one of {', '.join(FEEDBACK)}")
    spec = get_machine(machine)
    bm = build(machine, overrides)
    feedback = feedback or bm.feedback
    step = float(bm.model.opt.timestep)
    dt = control_period_s if control_period_s is not None else max(1, round(CONTROL_PERIOD_S / step)) * step
    ratio = dt / step
    if abs(ratio - round(ratio)) > 1e-6 or round(ratio) < 1:
        raise TwinInputError("--control-period", dt, f"must be a whole multiple of the timestep {step:g} s")
    axes = {}
    for i, a in enumerate(bm.axes):
        velocity, position = (
            "motor" if joint == a.motor_joint else "table"
            for joint in (a.velocity_joint(feedback), a.encoder_joint(feedback))
        )
        axes[a.name] = tune_axis(
            bm, i, dt, resonances_hz=model_modes(bm, i, velocity)[0], velocity_sensor=velocity, position_sensor=position
        )
    return {
        "machine": machine,
        "machine_name": spec.name,
        "control_period_s": dt,
        "feedback": feedback,
        "targets": {"phase_margin_deg": PHASE_MARGIN_DEG, "gain_margin_db": GAIN_MARGIN_DB},
        "overrides": dict(overrides or {}),
        "axes": axes,
    }


#: The verification's circle: radius (mm) and feed (mm/min); a one-axis machine runs its
#: projection on the axis, a sine of the radius's amplitude at feed / (2 pi radius).
CIRCLE_RADIUS_MM = 10.0
CIRCLE_FEED_MM_PER_MIN = 2000.0


def scenario_text(result: dict, machine_path: str, reference: str = "circle") -> str:
    """The tuned cascade as a scenario TOML (a circle of 10 mm at 2 m/min, on a one-axis machine
    its projection on the axis; or a 1 mm step)."""
    lines = [
        f'name = "tuned_{result["machine_name"]}"',
        f'description = "twin tune: position P / velocity PI cascade with feedforward on {result["machine_name"]}"',
        f'machine = "{machine_path}"',
        f"control_period_s = {result['control_period_s']!r}",
    ]
    if result["overrides"]:
        lines.append("overrides = { " + ", ".join(f"{k} = {v!r}" for k, v in result["overrides"].items()) + " }")
    if reference == "circle" and len(result["axes"]) == 1:
        frequency = CIRCLE_FEED_MM_PER_MIN / 60.0 / (2.0 * math.pi * CIRCLE_RADIUS_MM)
        lines += [
            "duration_s = 2.0",
            "",
            "[reference]  # the 10 mm circle at 2 m/min projected on the axis",
            'type = "sines"',
            f"amplitudes_m = [{CIRCLE_RADIUS_MM / 1e3!r}]",
            f"frequencies_hz = [{frequency!r}]",
        ]
    elif reference == "circle":
        lines += [
            "duration_s = 2.0",
            "",
            "[reference]",
            'type = "circle"',
            f"radius_mm = {CIRCLE_RADIUS_MM!r}",
            f"feed_mm_per_min = {CIRCLE_FEED_MM_PER_MIN!r}",
        ]
    else:
        lines += ["duration_s = 0.3", "", "[reference]", 'type = "step"', "amplitude_m = 0.001", "t0_s = 0.01"]
    lines += ["", "[sensors]", f'feedback = "{result["feedback"]}"']
    for a, r in result["axes"].items():
        lines += ["", f"[controllers.{a}]", 'type = "servo_cascade"', f"[controllers.{a}.params]"]
        lines += [f"{k} = {v!r}" for k, v in r["gains"].items()]
    return "\n".join(lines) + "\n"


def verify(result: dict, machine_path: str, folder: Path) -> dict:
    """Run the tuned cascade on the twin: a 1 mm step (overshoot %, 2 % settling time s) and
    a circle (max tracking and contour error, um)."""
    out: dict[str, dict[str, float]] = {}
    for reference in ("step", "circle"):
        path = folder / f"tuned_{reference}.toml"
        path.write_text(scenario_text(result, machine_path, reference), encoding="utf-8")
        outcome = run_scenario(load_scenario(path))
        run = outcome.run
        if reference == "step":
            y = run.table_position_m()
            t = run.t_s
            for k, a in enumerate(result["axes"]):
                final = 0.001
                over = 100 * (y[:, k].max() - final) / final
                outside = np.flatnonzero(np.abs(y[:, k] - final) > 0.02 * final)
                out.setdefault(a, {})["step_overshoot_pct"] = float(max(over, 0.0))
                out[a]["step_settling_s"] = float(t[outside[-1]] - 0.01) if outside.size else 0.0
        else:
            summary = tracking_summary(outcome)  # a one-axis machine's projection has no contour
            contour = ("max_contour_error_um", "rms_contour_error_um")
            out["circle"] = {
                **{key: summary[key] for key in contour if key in summary},
                **{f"max_tracking_error_um_{a}": v for a, v in summary["max_tracking_error_um"].items()},
            }
    return out
