"""Fidelity of each MJCF twin against its reference transfer-function model.

Three checks, all at the physics timestep as control period so that the reference can be the
*exact* zero-order-hold discretization of G(s) (``control.c2d(..., 'zoh')``) with the drive delay
as whole samples: the comparison then isolates the multibody model (constraint softness,
integrator) from the sampling itself.

(a) ``time_nrmse``: open-loop response to a test input (doublet + 3 Hz sine, each input in turn,
1 V or less where that would run past a fifth of the half travel);
    RMS(twin - TF) / RMS(TF) over every output, worst case.
(b) ``frf_max_mag_err_db`` / ``frf_max_phase_err_deg``: frequency response measured on the twin
    as on the real table (Maharof 2021): closed loop around the integrator with a proportional
    position controller, a periodic multisine reference (Schroeder phases, one tone per
    excited bin, 0.1-50 Hz), one experiment per axis, steady-state period only (after >= 5 s of settling), and the MIMO
    estimate G = Y U^-1 at each excited bin; compared with G's ZOH equivalent incl. delay.
(c) ``coupling_slip_um``: worst motor-screw-table kinematic mismatch (um of table travel)
    under a full-scale +-10 V reversal on every axis at once.

Friction is forced off (the reference models have none).

Besides one case per machine, ``linear_motor_xy+average_force`` runs ``linear_motor_xy`` with
Choi 1999's average cutting force (:class:`twin.machining.cutting.AverageForce`, Table 1's nominal
k_il = -2500, k_c = 2500 N s/m, written into ``xfrc_applied`` every physics step) against the
coupled 4-state model of eq. (11) (:func:`controllers.papers.choi1999.cutting_coupled_plant`).
"""

from __future__ import annotations

import math
from typing import Any

import control
import numpy as np

from controllers.blocks import error_feedback, open_loop
from controllers.lti import SisoTf
from controllers.papers.choi1999 import cutting_coupled_plant
from twin.errors import TwinInputError
from twin.machines import MACHINES, build, get_machine, is_machine_file
from twin.machining.cutting import AverageForce
from twin.references import Step, SumOfSines
from twin.sim.runner import simulate

TARGETS = {"time_nrmse": 0.005, "frf_max_mag_err_db": 0.2, "frf_max_phase_err_deg": 2.0, "coupling_slip_um": 0.1}
FULL_SCALE_V = 10.0
#: Longest settling (s) the frequency check waits for before its measured periods.
MAX_SETTLE_S = 600.0
#: Choi 1999 Table 1, up milling (N s/m).
CHOI1999_CUTTING = AverageForce(k_il_N_s_per_m=-2500.0, k_c_N_s_per_m=2500.0)
#: Fidelity cases: name -> (machine, cutting-force model or None).
CASES = {
    **{name: (name, None) for name in MACHINES},
    "linear_motor_xy+average_force": ("linear_motor_xy", CHOI1999_CUTTING),
}


def case_machine(case: str) -> tuple[str, AverageForce | None]:
    """The machine (a name or a machine file) and cutting-force model of a fidelity case: one of
    :data:`CASES`, or a machine file (``.toml``, no cutting).

    Raises
    ------
    TwinInputError
        Neither a case nor a readable machine file.
    """
    if is_machine_file(case):
        get_machine(case)
        return case, None
    if case not in CASES:
        raise TwinInputError(
            "machine", case, f"unknown fidelity case (known: {', '.join(CASES)}; or a machine file, FILE.toml)"
        )
    return CASES[case]


def _discrete_reference(bm, reference, dt):
    """ZOH-exact state-space model of the reference at ``dt``, with the drive delay in samples."""
    g = control.c2d(control.ss(reference), dt, "zoh")
    return g, round(bm.delay_s / dt)


def _tf_listing(bm, reference) -> dict:
    names = [a.name for a in bm.axes]
    plant = control.tf(reference)
    out = {}
    for i, yi in enumerate(names):
        for j, uj in enumerate(names):
            num = np.trim_zeros(np.asarray(plant.num[i][j], float), "f")
            if not (np.abs(num) > 1e-12 * np.abs(plant.den[i][j]).max()).any():
                continue
            key = yi if len(names) == 1 or i == j else f"{yi}<-u_{uj}"
            out[key] = {"num": num.tolist(), "den": np.asarray(plant.den[i][j], float).tolist(), "delay_s": bm.delay_s}
    return out


def time_response_nrmse(bm, reference, duration_s: float = 1.0, disturbances=()) -> float:
    """Check (a): worst normalized RMS error of the open-loop response against ``reference``
    (a python-control model, V to m)."""
    dt = bm.model.opt.timestep
    n_axes = len(bm.axes)
    n = round(duration_s / dt)
    t = np.arange(n) * dt
    test = np.where(t < 0.2, 1.0, np.where(t < 0.4, -1.0, 0.0)) + 0.5 * np.sin(2 * math.pi * 3.0 * t)
    g, delay = _discrete_reference(bm, reference, dt)
    worst = 0.0
    for k in range(n_axes):
        u = np.zeros((n, n_axes))
        u[:, k] = test
        u_delayed = np.vstack([np.zeros((delay, n_axes)), u[: n - delay]]) if delay else u
        y_ref = np.atleast_2d(control.forced_response(g, T=t, U=u_delayed.T).outputs).T
        # a light, strong axis would run the 1 V doublet into its travel's end (the model has
        # none): scaled to move at most a fifth of the half travel, as the (linear) model predicts it
        table = bm.model.joint(bm.axes[k].table_joint)
        half_travel = 0.5 * float(table.range[1] - table.range[0]) if table.limited[0] else math.inf
        scale = min(1.0, 0.2 * half_travel / float(np.abs(y_ref).max()))
        u, y_ref = scale * u, scale * y_ref
        res = simulate(
            bm,
            open_loop(u, dt, [a.name for a in bm.axes]),
            Step(0.0, n_axes=n_axes),
            duration_s,
            dt,
            disturbances=disturbances,
            progress=False,
            record_every=1,
        )
        err = res.table_position_m() - y_ref
        worst = max(worst, float(np.sqrt(np.mean(err**2)) / np.sqrt(np.mean(y_ref**2))))
    return worst


def multisine_bins(period_s: float, f_min_hz: float, f_max_hz: float, n_tones: int) -> np.ndarray:
    """Excited DFT bins (integers): log-spaced over the band, one tone per bin."""
    k_min, k_max = max(1, round(f_min_hz * period_s)), round(f_max_hz * period_s)
    return np.unique(np.round(np.geomspace(k_min, k_max, n_tones)).astype(int))


def frequency_response_errors(
    bm,
    reference,
    *,
    period_s: float = 10.0,
    f_max_hz: float = 50.0,
    n_tones: int = 40,
    crossover_hz: float = 2.0,
    settle_s: float = 5.0,
    disturbances=(),
) -> dict:
    """Check (b): measured frequency response against ``reference`` (a python-control model,
    V to m), worst magnitude (dB) and phase (deg)."""
    dt = bm.model.opt.timestep
    n_axes = len(bm.axes)
    bins = multisine_bins(period_s, 1.0 / period_s, f_max_hz, n_tones)
    freqs = bins / period_s
    n_period = round(period_s / dt)
    # one position controller per axis (minimal realizations: a channel of a MIMO model
    # carries the other axes' integrators); the loop must settle: wait until its slowest
    # transient has decayed by e^-12 (6e-6)
    channels = [control.minreal(reference[i, i], verbose=False) for i in range(n_axes)]
    designs = [position_controller(channel, crossover_hz, settle_s) for channel in channels]
    decay = min(d for _, d in designs)
    if decay < 12.0 / MAX_SETTLE_S:
        raise TwinInputError(
            "machine",
            bm.name,
            f"its proportional position loop settles in over {MAX_SETTLE_S:g} s (slowest decay {decay:.3g} 1/s):"
            " the frequency check needs some viscous friction",
        )
    settle = max(1, math.ceil(max(settle_s, 12.0 / decay) / period_s))  # whole periods discarded as transient
    # In steady state the linear loop's signals hold the excited tones only (<= f_max_hz): a
    # record every ``every`` ticks, SAMPLES_PER_TONE_PERIOD a period of the highest tone and a
    # divisor of the period, gives the same bins (both Y and U scaled by 1/every), without
    # aliasing, at a fraction of the memory (mid_size_xy at 50 us: 1.6 GB recorded before).
    every = _record_every(n_period, dt, f_max_hz)
    phases = -math.pi * bins * (bins - 1) / len(bins)  # Schroeder: low crest factor
    Y = np.zeros((len(bins), n_axes, n_axes), complex)
    U = np.zeros((len(bins), n_axes, n_axes), complex)
    for k in range(n_axes):
        amp = tone_amplitude_m(channels[k], crossover_hz)
        ref = SumOfSines((amp,) * len(bins), tuple(freqs), tuple(phases), n_axes=n_axes, axes=(k,))
        ctrls = [error_feedback(designs[i][0], dt, axes=(a.name,), name=f"P.{a.name}") for i, a in enumerate(bm.axes)]
        res = simulate(
            bm, ctrls, ref, (settle + 1) * period_s, dt, disturbances=disturbances, progress=False, record_every=every
        )
        y = res.table_position_m()[settle * n_period // every :]
        u = res.u_applied_V[settle * n_period // every :]
        Y[:, :, k] = np.fft.rfft(y, axis=0)[bins]
        U[:, :, k] = np.fft.rfft(u, axis=0)[bins]
    G_meas = Y @ np.linalg.inv(U)
    g, delay = _discrete_reference(bm, reference, dt)
    z = np.exp(2j * math.pi * freqs * dt)
    G_ref = np.stack([g(zi) * zi ** (-delay) for zi in z]).reshape(len(bins), n_axes, n_axes)
    diag = np.arange(n_axes)
    ratio = G_meas[:, diag, diag] / G_ref[:, diag, diag]
    out = {
        "frf_max_mag_err_db": float(np.abs(20 * np.log10(np.abs(ratio))).max()),
        "frf_max_phase_err_deg": float(np.abs(np.degrees(np.angle(ratio))).max()),
        "frf_band_hz": [float(freqs[0]), float(freqs[-1])],
        "frf_tones": len(bins),
    }
    off = ~np.eye(n_axes, dtype=bool)
    if n_axes > 1 and np.abs(G_ref[:, off]).max() > 0:
        # cross-coupling channels: relative complex error against the direct channel's size
        scale = np.abs(G_ref[:, diag, diag]).min(axis=1, keepdims=True)
        out["frf_cross_max_rel_err"] = float((np.abs(G_meas[:, off] - G_ref[:, off]) / scale).max())
    return out


def coupling_slip_um(bm, duration_s: float = 0.4) -> float:
    """Check (c): worst gear-coupling mismatch (um) under a +-10 V reversal on all axes."""
    if not bm.couplings:
        return 0.0
    dt = bm.model.opt.timestep
    n = round(duration_s / dt)
    n_axes = len(bm.axes)
    u = np.full((n, n_axes), FULL_SCALE_V)
    u[n // 2 :] = -FULL_SCALE_V
    res = simulate(
        bm,
        open_loop(u, dt, [a.name for a in bm.axes]),
        Step(0.0, n_axes=n_axes),
        duration_s,
        dt,
        progress=False,
        record_every=1,
    )
    return float(bm.slip_m(res.qpos).max() * 1e6)


#: The lead of the frequency check's controller where a proportional loop rings: its zero this
#: factor below the crossover, its pole this factor above (about 53 deg of phase at crossover).
LEAD_FACTOR = 3.0


def position_controller(channel, crossover_hz: float, settle_s: float) -> tuple[SisoTf, float]:
    """The frequency check's position controller for one axis's ``channel`` (V to m) and its
    closed loop's slowest decay (1/s): a gain with loop gain 1 at ``crossover_hz``; where that
    loop rings longer than ``settle_s`` (a heavy table with little viscous friction: a double
    integrator under a proportional gain decays at b / 2m, 0.1/s on mid_size_xy, 130 s to
    settle), a lead that damps it.  The estimate G = Y U^-1 does not depend on the controller;
    only the time the check spends waiting does."""
    w = 2 * math.pi * crossover_hz
    kp = 1.0 / abs(channel(1j * w))
    p_only = SisoTf((kp,), (1.0,))
    decay = -control.poles(control.feedback(kp * channel)).real.max()
    if decay * settle_s >= 12.0:  # (a frictionless double integrator's decay is 0)
        return p_only, decay
    zero, pole = w / LEAD_FACTOR, w * LEAD_FACTOR
    shape = control.tf([1.0 / zero, 1.0], [1.0 / pole, 1.0])
    gain = 1.0 / abs(channel(1j * w) * shape(1j * w))
    lead = SisoTf((gain / zero, gain), (1.0 / pole, 1.0))
    lead_decay = -control.poles(control.feedback(gain * shape * channel)).real.max()
    return (lead, lead_decay) if lead_decay > decay else (p_only, decay)


def tone_amplitude_m(channel, crossover_hz: float) -> float:
    """Each tone's amplitude (m) in the frequency check's reference for an axis's ``channel`` (V to
    m): about 0.2 V per tone at high frequency under a gain with loop gain 1 at ``crossover_hz``
    (a lead's 3x that). Taken from the plant, whatever the controller: a lead's lower gain at low
    frequency made the tones 3x larger, and compact_xy's Y table ran past its travel (its
    lowest bins 1.7 dB / 157 deg off)."""
    kp = 1.0 / abs(channel(2j * math.pi * crossover_hz))  # the gain with loop gain 1 at the crossover
    return 0.2 / kp


#: Recorded samples per period of the highest tone in the frequency check, at least.
SAMPLES_PER_TONE_PERIOD = 8


def _record_every(n_period: int, dt: float, f_max_hz: float) -> int:
    """The largest divisor of ``n_period`` (ticks) that still records
    :data:`SAMPLES_PER_TONE_PERIOD` samples per period of ``f_max_hz`` at the tick ``dt``."""
    most = max(1, int(1.0 / (SAMPLES_PER_TONE_PERIOD * f_max_hz * dt)))
    return max(k for k in range(1, most + 1) if n_period % k == 0)


def fidelity(case: str, overrides: dict | None = None, *, frf_period_s: float = 10.0, frf_tones: int = 40) -> dict:
    """All three checks for one case of :data:`CASES` (a machine name, or a machine with a
    cutting-force model) or a machine file; see the module docstring.

    Returns
    -------
    dict
        ``machine``, ``case``, ``overrides``, ``tf``, ``time_nrmse``, ``frf_max_mag_err_db``,
        ``frf_max_phase_err_deg``, ``coupling_slip_um``, ``targets``, ``pass`` and details.

    Raises
    ------
    TwinInputError
        Unknown case.
    """
    machine, cutting = case_machine(case)
    overrides = dict(overrides or {})
    spec = get_machine(machine)
    forced = {s: 0.0 for s in spec.coulomb_symbols()}
    bm = build(machine, {**overrides, **forced})
    reference = bm.plant_lti()
    disturbances: tuple = ()
    if cutting is not None:
        reference = control.ss(*cutting_coupled_plant(bm.params, cutting.k_il_N_s_per_m, cutting.k_c_N_s_per_m))
        disturbances = (cutting,)
    out: dict[str, Any] = {
        "machine": machine,
        "case": case,
        "overrides": overrides,
        "friction_forced_off": sorted(forced),
        "tf": _tf_listing(bm, reference),
        "time_nrmse": time_response_nrmse(bm, reference, disturbances=disturbances),
    }
    out.update(
        frequency_response_errors(bm, reference, period_s=frf_period_s, n_tones=frf_tones, disturbances=disturbances)
    )
    out["coupling_slip_um"] = coupling_slip_um(bm)
    out["targets"] = TARGETS
    out["pass"] = all(out[k] <= v for k, v in TARGETS.items())
    return out
