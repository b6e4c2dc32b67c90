"""Milling forces on the workpiece, written into ``MjData.xfrc_applied`` before every physics step.

Two models, both driven by the workpiece's actual motion (the spindle is fixed in the world,
so the tool feeds relative to the workpiece at ``-v_workpiece``), so the process couples to
the drive:

:class:`EndMilling`
    The mechanistic end-milling model of the machining literature (Altintas, *Manufacturing
    Automation*, 2nd ed., ch. 2.5, straight flutes, linear edge-force model).  Flute ``j`` at
    immersion angle ``phi_j`` (measured clockwise from the feed-normal axis) cuts a chip of
    thickness ``h = c sin(phi_j)`` while ``phi_st <= phi_j <= phi_ex``, with ``c`` the feed
    per tooth; its tangential, radial and axial forces are
    ``F_t = K_tc a h + K_te a``, ``F_r = K_rc a h + K_re a``, ``F_a = K_ac a h + K_ae a``
    (``a`` axial depth).  In the feed frame (x along the feed, y = z x feed, z up the spindle,
    the cutter turning clockwise seen from the spindle) the force on the tool is
    ``F_x = -F_t cos(phi) - F_r sin(phi)``, ``F_y = F_t sin(phi) - F_r cos(phi)``, ``F_z = F_a``;
    the workpiece gets the opposite.  Up milling engages ``0 <= phi <= arccos(1 - 2 a_e/D)``,
    down milling ``arccos(2 a_e/D - 1) <= phi <= pi``; a slot (``a_e = D``) engages ``0..pi``.
    The feed per tooth and its direction come from the workpiece's displacement over the last
    tooth period.  The material is assumed to lie ahead of the tool in whatever direction it
    feeds (the model does not track the workpiece geometry): a reversal re-engages the same way.
:class:`AverageForce`
    Seed 004's average-force model, eqs. (2)-(5) and the A matrix of eq. (11):
    ``F_x = k_il v_x - k_c v_y``, ``F_y = k_il v_y + k_c v_x`` (N, with ``k_il``, ``k_c`` in
    N s/m; Table 1 for up milling: ``k_il = -2500``, ``k_c = 2500``), optionally times
    ``1 + r sin(2 pi f_tooth t + phase)`` with ``r <= 0.2``: the paper's bound on the cyclic
    component (Golub 1992).  Eqs. (6)-(7) print ``k_il v_x`` without the ``1/m_x`` that
    eq. (11)'s A matrix carries; the twin follows eq. (11), where the gains are forces per
    velocity (N s/m) as the paper's units say.

Default cutting coefficients: aluminium Al7075-T6 with a carbide cutter, dry:
K_tc 767.01, K_rc 168.8, K_ac 222 N/mm^2, K_te 27.7, K_re 26.6, K_ae 0.7 N/mm, as tabulated
in Table 5 of "Milling force model for aviation aluminum alloy: academic insight and
perspective analysis", Chinese J. Mech. Eng. 34 (2021) 98, doi:10.1186/s10033-021-00536-9
(its ref. [190]).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from twin.errors import TwinInputError

#: Feed per tooth (m) below which the feed direction is held at its last value.
MIN_FEED_M = 1e-9


@dataclass(frozen=True)
class CuttingCoefficients:
    """Mechanistic cutting (N/mm^2) and edge (N/mm) force coefficients."""

    K_tc: float
    K_rc: float
    K_ac: float
    K_te: float
    K_re: float
    K_ae: float


#: Al7075-T6, carbide, dry (see the module docstring for the source).
ALUMINIUM_7075_T6 = CuttingCoefficients(K_tc=767.01, K_rc=168.8, K_ac=222.0, K_te=27.7, K_re=26.6, K_ae=0.7)
MATERIALS = {"aluminium_7075_t6": ALUMINIUM_7075_T6}


def immersion_angles(radial_depth_mm: float, diameter_mm: float, mode: str) -> tuple[float, float]:
    """Entry and exit angles ``(phi_st, phi_ex)`` (rad) of a radial immersion.

    Parameters
    ----------
    radial_depth_mm, diameter_mm : float
        Radial depth of cut ``a_e`` and cutter diameter ``D`` (mm), ``0 < a_e <= D``.
    mode : {"up", "down"}
        Up (conventional) or down (climb) milling; equal for a slot (``a_e = D``).
    """
    if not 0 < radial_depth_mm <= diameter_mm:
        raise TwinInputError("radial_depth_mm", radial_depth_mm, f"must be in (0, diameter_mm = {diameter_mm}]")
    ratio = radial_depth_mm / diameter_mm
    if mode == "up":
        return 0.0, math.acos(1.0 - 2.0 * ratio)
    if mode == "down":
        return math.acos(2.0 * ratio - 1.0), math.pi
    raise TwinInputError("mode", mode, "must be 'up' or 'down'")


def flute_force_integral(k: CuttingCoefficients, axial_depth_mm: float, feed_per_tooth_mm: float,
                         phi: float) -> tuple[float, float, float]:
    """Primitive ``Q(phi)`` of one engaged flute's force on the tool over its angle (N rad).

    With ``h = c sin(phi)``, ``F_x = -F_t cos(phi) - F_r sin(phi)``, ``F_y = F_t sin(phi) - F_r cos(phi)``
    and ``F_z = F_a``:
    ``Q_x = a c/4 [K_tc cos 2phi - K_rc (2phi - sin 2phi)] + a [-K_te sin phi + K_re cos phi]``,
    ``Q_y = a c/4 [K_tc (2phi - sin 2phi) + K_rc cos 2phi] - a [K_te cos phi + K_re sin phi]``,
    ``Q_z = a [-K_ac c cos phi + K_ae phi]``.
    """
    a, c = axial_depth_mm, feed_per_tooth_mm
    s2, c2 = math.sin(2.0 * phi), math.cos(2.0 * phi)
    s1, c1 = math.sin(phi), math.cos(phi)
    qx = a * c / 4.0 * (k.K_tc * c2 - k.K_rc * (2.0 * phi - s2)) + a * (-k.K_te * s1 + k.K_re * c1)
    qy = a * c / 4.0 * (k.K_tc * (2.0 * phi - s2) + k.K_rc * c2) - a * (k.K_te * c1 + k.K_re * s1)
    qz = a * (-k.K_ac * c * c1 + k.K_ae * phi)
    return qx, qy, qz


def mean_tool_forces_N(k: CuttingCoefficients, n_flutes: int, axial_depth_mm: float,
                       feed_per_tooth_mm: float, phi_st: float, phi_ex: float) -> np.ndarray:
    """Closed-form average force on the tool over a tooth period, feed frame (N), shape (3,).

    ``N/(2 pi) [Q(phi_ex) - Q(phi_st)]`` with :func:`flute_force_integral` (Altintas eq. 2.64).
    """
    hi = flute_force_integral(k, axial_depth_mm, feed_per_tooth_mm, phi_ex)
    lo = flute_force_integral(k, axial_depth_mm, feed_per_tooth_mm, phi_st)
    return n_flutes / (2.0 * math.pi) * (np.array(hi) - np.array(lo))


def step_tool_forces_N(k: CuttingCoefficients, n_flutes: int, axial_depth_mm: float, feed_per_tooth_mm: float,
                       phi_st: float, phi_ex: float, spindle_angle_rad: float,
                       step_angle_rad: float) -> tuple[float, float, float]:
    """Force on the tool, feed frame (N), averaged over one physics step, summed over the flutes.

    Flute 0 turns from ``spindle_angle_rad`` through ``step_angle_rad`` (> 0) during the step;
    flute j trails it by ``2 pi j/N``.  The average is exact (the integral of
    :func:`flute_force_integral` over the engaged part of the step), so the force the twin
    applies carries the same impulse as the continuous model, whatever the timestep.
    """
    fx = fy = fz = 0.0
    two_pi = 2.0 * math.pi
    pitch = two_pi / n_flutes
    for j in range(n_flutes):
        start = (spindle_angle_rad - j * pitch) % two_pi
        for shift in (0.0, -two_pi):  # the step may wrap past 2 pi into the next revolution
            lo = max(start + shift, phi_st)
            hi = min(start + shift + step_angle_rad, phi_ex)
            if hi > lo:
                qh = flute_force_integral(k, axial_depth_mm, feed_per_tooth_mm, hi)
                ql = flute_force_integral(k, axial_depth_mm, feed_per_tooth_mm, lo)
                fx += qh[0] - ql[0]
                fy += qh[1] - ql[1]
                fz += qh[2] - ql[2]
    return fx / step_angle_rad, fy / step_angle_rad, fz / step_angle_rad


def _active(start_s: float, stop_s: float | None, timestep_s: float = 0.0):
    """Predicate ``start_s <= t < stop_s`` on a step's start time, with half a step of slack
    for the rounding of MuJoCo's accumulated ``data.time``."""
    if not start_s >= 0:
        raise TwinInputError("start_s", start_s, "must be >= 0")
    if stop_s is not None and not stop_s > start_s:
        raise TwinInputError("stop_s", stop_s, f"must be > start_s = {start_s}")
    lo = start_s - 0.5 * timestep_s
    hi = math.inf if stop_s is None else stop_s - 0.5 * timestep_s
    return lambda t: lo <= t < hi


def _check_cutter(spindle_rpm: float, n_flutes: int) -> None:
    """Spindle speed (rev/min) > 0 and a whole number of flutes >= 1."""
    if not spindle_rpm > 0:
        raise TwinInputError("spindle_rpm", spindle_rpm, "must be > 0")
    if int(n_flutes) != n_flutes or n_flutes < 1:
        raise TwinInputError("n_flutes", n_flutes, "must be a whole number >= 1")


def _tooth_frequency_hz(spindle_rpm: float, n_flutes: int) -> float:
    """Tooth-passing frequency N rpm / 60 (Hz)."""
    return n_flutes * spindle_rpm / 60.0


def _spindle_phase(phase_rad: float | None, seed: int) -> float:
    """The given initial spindle angle, or one drawn from ``seed`` (rad)."""
    if phase_rad is not None:
        return float(phase_rad)
    return float(np.random.default_rng(seed).uniform(0.0, 2.0 * math.pi))


@dataclass(frozen=True)
class EndMilling:
    """Mechanistic end milling on the workpiece (see the module docstring).

    Parameters
    ----------
    spindle_rpm : float
        Spindle speed (rev/min).
    n_flutes : int
    diameter_mm, axial_depth_mm, radial_depth_mm : float
        Cutter diameter ``D``, axial depth ``a``, radial depth ``a_e`` (mm).
    mode : {"up", "down"}
    coefficients : CuttingCoefficients
        Default Al7075-T6.
    start_s, stop_s : float
        The tool is engaged for ``start_s <= t < stop_s`` (s); ``stop_s`` None: to the end.
    spindle_phase_rad : float or None
        Flute 0's immersion angle at t = 0; None draws it from ``seed``.
    seed : int
    """

    spindle_rpm: float
    n_flutes: int
    diameter_mm: float
    axial_depth_mm: float
    radial_depth_mm: float
    mode: str = "up"
    coefficients: CuttingCoefficients = ALUMINIUM_7075_T6
    start_s: float = 0.0
    stop_s: float | None = None
    spindle_phase_rad: float | None = None
    seed: int = 0

    def __post_init__(self):
        _check_cutter(self.spindle_rpm, self.n_flutes)
        for name in ("diameter_mm", "axial_depth_mm"):
            if not getattr(self, name) > 0:
                raise TwinInputError(name, getattr(self, name), "must be > 0")
        immersion_angles(self.radial_depth_mm, self.diameter_mm, self.mode)
        _active(self.start_s, self.stop_s)

    @property
    def tooth_frequency_hz(self) -> float:
        """Tooth-passing frequency N rpm / 60 (Hz)."""
        return _tooth_frequency_hz(self.spindle_rpm, self.n_flutes)

    def step_hook(self, machine):
        """A ``hook(model, data)`` for the runner that adds the force before each ``mj_step``.

        The feed per tooth and its direction are the workpiece's displacement over the last
        tooth period, ``c = |r(t - T) - r(t)|`` (linear interpolation between physics steps;
        the pose at t = 0 before that): the chip the previous flute left.  Vibration of the
        table at the tooth frequency and its harmonics cancels out of it, as in the
        regenerative chip-thickness model with a rigid tool.
        """
        k, N, a = self.coefficients, int(self.n_flutes), self.axial_depth_mm
        phi_st, phi_ex = immersion_angles(self.radial_depth_mm, self.diameter_mm, self.mode)
        dt = machine.model.opt.timestep
        omega = 2.0 * math.pi * self.spindle_rpm / 60.0
        lag_steps = 1.0 / self.tooth_frequency_hz / dt
        lag_lo = int(lag_steps)
        frac = lag_steps - lag_lo
        history = np.empty((lag_lo + 2, 2))  # ring buffer of workpiece positions (m)
        phase0 = _spindle_phase(self.spindle_phase_rad, self.seed)
        active = _active(self.start_s, self.stop_s, dt)
        jac = machine.workpiece_jacobian()
        wp = machine.workpiece_body_id
        state = {"step": 0, "feed": (1.0, 0.0)}  # feed: unit direction, held through stops

        def hook(model, data):
            i = state["step"]
            state["step"] = i + 1
            n = len(history)
            history[i % n] = jac @ data.qpos
            if i == 0:
                history[:] = history[0]
            if not active(data.time):
                return
            # position one tooth period ago, between steps i - lag_lo - 1 and i - lag_lo
            p0, p1 = history[max(i - lag_lo, 0) % n], history[max(i - lag_lo - 1, 0) % n]
            dx = (1.0 - frac) * p0[0] + frac * p1[0] - history[i % n, 0]
            dy = (1.0 - frac) * p0[1] + frac * p1[1] - history[i % n, 1]
            c_m = math.hypot(dx, dy)
            if c_m > MIN_FEED_M:
                state["feed"] = (dx / c_m, dy / c_m)
            ux, uy = state["feed"]
            fx, fy, fz = step_tool_forces_N(k, N, a, c_m * 1e3, phi_st, phi_ex, phase0 + omega * data.time,
                                            omega * dt)
            f = data.xfrc_applied[wp]
            # feed frame -> world; the workpiece gets the reaction of the force on the tool
            f[0] -= fx * ux - fy * uy
            f[1] -= fx * uy + fy * ux
            f[2] -= fz
        return hook


@dataclass(frozen=True)
class AverageForce:
    """Seed 004's average cutting force ``F = k_il v + k_c (z x v)`` on the workpiece (N).

    Parameters
    ----------
    k_il_N_s_per_m, k_c_N_s_per_m : float
        In-line and cross-coupling force gains (N s/m); Table 1: -2500 and 2500 (up milling).
    harmonic_fraction : float
        Amplitude of the tooth-passing harmonic relative to the average force, 0..0.2.
    spindle_rpm : float, n_flutes : int
        Set the tooth-passing frequency of the harmonic.
    start_s, stop_s : float
        Engaged for ``start_s <= t < stop_s`` (s).
    harmonic_phase_rad : float or None
        Phase of the harmonic at t = 0; None draws it from ``seed``.
    seed : int
    """

    k_il_N_s_per_m: float = -2500.0
    k_c_N_s_per_m: float = 2500.0
    harmonic_fraction: float = 0.0
    spindle_rpm: float = 10000.0
    n_flutes: int = 2
    start_s: float = 0.0
    stop_s: float | None = None
    harmonic_phase_rad: float | None = None
    seed: int = 0

    def __post_init__(self):
        for name in ("k_il_N_s_per_m", "k_c_N_s_per_m"):
            if not math.isfinite(getattr(self, name)):
                raise TwinInputError(name, getattr(self, name), "must be finite")
        if not 0 <= self.harmonic_fraction <= 0.2:
            raise TwinInputError("harmonic_fraction", self.harmonic_fraction,
                                 "must be in [0, 0.2]: seed 004 bounds the cyclic part at 20 % of the average")
        _check_cutter(self.spindle_rpm, self.n_flutes)
        _active(self.start_s, self.stop_s)

    def step_hook(self, machine):
        """A ``hook(model, data)`` for the runner that adds the force before each ``mj_step``."""
        k_il, k_c, r = self.k_il_N_s_per_m, self.k_c_N_s_per_m, self.harmonic_fraction
        w = 2.0 * math.pi * _tooth_frequency_hz(self.spindle_rpm, self.n_flutes)
        phase = _spindle_phase(self.harmonic_phase_rad, self.seed)
        active = _active(self.start_s, self.stop_s, machine.model.opt.timestep)
        jac = machine.workpiece_jacobian()
        wp = machine.workpiece_body_id

        def hook(model, data):
            if not active(data.time):
                return
            f = data.xfrc_applied[wp]
            vx, vy = jac @ data.qvel
            gain = 1.0 + r * math.sin(w * data.time + phase) if r else 1.0
            f[0] += gain * (k_il * vx - k_c * vy)
            f[1] += gain * (k_il * vy + k_c * vx)
        return hook
