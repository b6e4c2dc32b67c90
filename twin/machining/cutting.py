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
    Choi 1999's average-force model, eqs. (2)-(5) and the A matrix of eq. (11):
    ``F_x = k_il v_x - k_c v_y``, ``F_y = k_il v_y + k_c v_x`` (N, with ``k_il``, ``k_c`` in
    N s/m; Table 1 for up milling: ``k_il = -2500``, ``k_c = 2500``), optionally times
    ``1 + r sin(2 pi f_tooth t + phase)`` with ``r <= 0.2``: the paper's bound on the cyclic
    component (Golub 1992).  Eqs. (6)-(7) print ``k_il v_x`` without the ``1/m_x`` that
    eq. (11)'s A matrix carries; the twin follows eq. (11), where the gains are forces per
    velocity (N s/m) as the paper's units say.

Default cutting coefficients: aluminium Al7075-T6 with a carbide cutter, dry:
K_tc 767.01, K_rc 168.8, K_ac 222 N/mm^2, K_te 27.7, K_re 26.6, K_ae 0.7 N/mm
(:mod:`twin.machining.materials`, with the other materials and their sources).

A Kienzle material (``kc = kc1 h^-mc``, the coefficients' ``mc > 0``) reaches the same closed
forms linearised: each step, its cutting coefficients are taken at the mean chip thickness of
the engaged arc at the step's feed per tooth, ``h_m = c (cos phi_st - cos phi_ex)/(phi_ex -
phi_st)`` (:func:`kienzle_coefficients`).  The mean force over a tooth period, and so the mean
power, is then ``kc(h_m)`` times the chip area, as in the tool makers' power formulas the
entries come from; the force's shape within the arc stays ``sin(phi)`` where Kienzle's is
``sin(phi)^(1 - mc)`` (the closed forms, exact impulse per step and helical flutes included,
need a force linear in h).  The linear coefficients (``mc = 0``) skip it: their forces are
those of the model above, bit for bit.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Literal

import numpy as np
from numba import njit
from pydantic import Field, model_validator

from twin.errors import TwinInputError
from twin.machining.materials import DEFAULT_MATERIAL, MATERIALS, CuttingCoefficients, kienzle
from twin.machining.tool_dynamics import ToolDynamicsSpec
from twin.numba_cache import configure as configure_numba_cache
from twin.spec import StrictSpec

configure_numba_cache()  # before the first @njit(cache=True): see twin.numba_cache

#: Planned feed speed (m/s) below which the feed direction is held at its last value.
MIN_FEED_M_PER_S = 1e-6
#: Helix angles at and above this (deg) are refused: end mills go to about 45 to 55 deg.
MAX_HELIX_DEG = 60.0


def helix_lag_rad_per_mm(helix_deg: float, diameter_mm: float) -> float:
    """How far a helical flute's edge lags its tip per height (rad/mm): ``2 tan(helix)/D``."""
    return 2.0 * math.tan(math.radians(helix_deg)) / diameter_mm


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


@njit(cache=True, inline="always")
def kienzle_coefficients(k, feed_per_tooth_mm, phi_st, phi_ex):  # pragma: no cover - compiled
    """``k`` (:meth:`CuttingCoefficients.as_array`) itself if its ``mc`` (``k[6]``) is 0, else a
    copy with the cutting coefficients times ``h_m^-mc``: the Kienzle form linearised about the
    mean chip thickness ``h_m = c (cos phi_st - cos phi_ex)/(phi_ex - phi_st)`` (mm) of the arc
    at feed per tooth ``c`` (mm); unchanged where no chip is cut (``h_m <= 0``)."""
    mc = k[6]
    if mc == 0.0:
        return k
    span = phi_ex - phi_st
    h_m = feed_per_tooth_mm * (math.cos(phi_st) - math.cos(phi_ex)) / span if span > 0.0 else 0.0
    if not h_m > 0.0:
        return k
    out = k.copy()
    scale = h_m**-mc
    for i in range(3):
        out[i] = k[i] * scale
    return out


@njit(cache=True)
def flute_force_integral(k, axial_depth_mm, du, dw, phi):  # pragma: no cover - compiled
    """Primitive ``Q(phi)`` of one engaged flute's force on the tool over its angle (N rad).

    ``k`` is :meth:`CuttingCoefficients.as_array`; the chip is ``h = du sin(phi) + dw cos(phi)``
    (mm): the projection of the chip vector ``(du, dw)`` (feed frame, mm) on the edge's outward
    normal ``n(phi) = (sin phi, cos phi)`` (``du = c``, ``dw = 0``: the feed per tooth ``c``
    alone).  With ``F_t = a (K_tc h + K_te)``, ``F_r = a (K_rc h + K_re)``,
    ``F_x = -F_t cos(phi) - F_r sin(phi)``, ``F_y = F_t sin(phi) - F_r cos(phi)``,
    ``F_z = a (K_ac h + K_ae)`` and ``S2 = phi/2 - sin(2phi)/4``, ``C2 = phi/2 + sin(2phi)/4``,
    ``SC = sin(phi)^2/2`` (the primitives of sin^2, cos^2, sin cos):
    ``Q_x = -a [K_tc (du SC + dw C2) + K_rc (du S2 + dw SC) + K_te sin phi - K_re cos phi]``,
    ``Q_y = a [K_tc (du S2 + dw SC) - K_rc (du SC + dw C2) - K_te cos phi - K_re sin phi]``,
    ``Q_z = a [K_ac (dw sin phi - du cos phi) + K_ae phi]``.
    """
    s1, c1 = math.sin(phi), math.cos(phi)
    s2 = math.sin(2.0 * phi)
    ss, cc, sc = phi / 2.0 - s2 / 4.0, phi / 2.0 + s2 / 4.0, s1 * s1 / 2.0
    a = axial_depth_mm
    qx = -a * (k[0] * (du * sc + dw * cc) + k[1] * (du * ss + dw * sc) + k[3] * s1 - k[4] * c1)
    qy = a * (k[0] * (du * ss + dw * sc) - k[1] * (du * sc + dw * cc) - k[3] * c1 - k[4] * s1)
    qz = a * (k[2] * (dw * s1 - du * c1) + k[5] * phi)
    return qx, qy, qz


def mean_tool_forces_N(
    k: CuttingCoefficients,
    *,
    n_flutes: int,
    axial_depth_mm: float,
    feed_per_tooth_mm: float,
    phi_st: float,
    phi_ex: float,
) -> np.ndarray:
    """Closed-form average force on the tool over a tooth period, feed frame (N), shape (3,).

    ``N/(2 pi) [Q(phi_ex) - Q(phi_st)]`` with :func:`flute_force_integral` (Altintas eq. 2.64);
    a Kienzle material's coefficients at the arc's mean chip thickness (:func:`kienzle_coefficients`).
    """
    ka = kienzle_coefficients(k.as_array(), feed_per_tooth_mm, phi_st, phi_ex)
    hi = flute_force_integral(ka, axial_depth_mm, feed_per_tooth_mm, 0.0, phi_ex)
    lo = flute_force_integral(ka, axial_depth_mm, feed_per_tooth_mm, 0.0, phi_st)
    return n_flutes / (2.0 * math.pi) * (np.array(hi) - np.array(lo))


@njit(cache=True)
def flute_force_double_integral(k, du, dw, phi):  # pragma: no cover - compiled
    """Primitive ``R(phi)`` of :func:`flute_force_integral` at unit axial depth (N rad^2/mm).

    With the primitives of ``S2``, ``C2``, ``SC``: ``phi^2/4 + cos(2phi)/8``,
    ``phi^2/4 - cos(2phi)/8``, ``phi/4 - sin(2phi)/8``:
    ``R_x = -[K_tc (du SC' + dw C2') + K_rc (du S2' + dw SC') - K_te cos phi - K_re sin phi]``,
    ``R_y = K_tc (du S2' + dw SC') - K_rc (du SC' + dw C2') - K_te sin phi + K_re cos phi``,
    ``R_z = -K_ac (du sin phi + dw cos phi) + K_ae phi^2/2`` (primes: those primitives).
    """
    s1, c1 = math.sin(phi), math.cos(phi)
    s2, c2 = math.sin(2.0 * phi), math.cos(2.0 * phi)
    p2 = phi * phi / 4.0
    ss, cc, sc = p2 + c2 / 8.0, p2 - c2 / 8.0, phi / 4.0 - s2 / 8.0
    rx = -(k[0] * (du * sc + dw * cc) + k[1] * (du * ss + dw * sc) - k[3] * c1 - k[4] * s1)
    ry = k[0] * (du * ss + dw * sc) - k[1] * (du * sc + dw * cc) - k[3] * s1 + k[4] * c1
    rz = -k[2] * (du * s1 + dw * c1) + k[5] * phi * phi / 2.0
    return rx, ry, rz


@njit(cache=True)
def _arc_ends(k, du, dw, phi_st, phi_ex, u_lo, u_hi):  # pragma: no cover - compiled
    """The primitives :func:`_clipped_double_integral` takes at the arc's ends for every ``u``
    in ``[u_lo, u_hi]``: ``Q(phi_st)`` (unit depth) where some ``u <= phi_st``, ``R(phi_st)``
    where some ``u > phi_st``, ``R(phi_ex)`` and ``Q(phi_ex)`` where some ``u >= phi_ex``; zeros
    for those no ``u`` there needs (each is evaluated once per flute and step, not once per
    ``u``)."""
    zero = (0.0, 0.0, 0.0)
    q_st = flute_force_integral(k, 1.0, du, dw, phi_st) if u_lo <= phi_st else zero
    r_st = flute_force_double_integral(k, du, dw, phi_st) if u_hi > phi_st else zero
    past_end = u_hi >= phi_ex
    r_ex = flute_force_double_integral(k, du, dw, phi_ex) if past_end else zero
    q_ex = flute_force_integral(k, 1.0, du, dw, phi_ex) if past_end else zero
    return q_st, r_st, r_ex, q_ex


@njit(cache=True)
def _clipped_double_integral(k, du, dw, phi_st, phi_ex, ends, u):  # pragma: no cover - compiled
    """``G(u)``: the integral up to ``u`` of ``Q(clip(psi, phi_st, phi_ex))`` at unit depth,
    zero at ``phi_st`` (N rad^2/mm): ``Q(phi_st) (u - phi_st)`` below the arc, ``R(u) - R(phi_st)``
    on it, ``R(phi_ex) - R(phi_st) + Q(phi_ex) (u - phi_ex)`` above it; ``ends`` the primitives
    at the arc's ends (:func:`_arc_ends`)."""
    q_st, r0, r_ex, q_ex = ends
    if u <= phi_st:
        d = u - phi_st
        return q_st[0] * d, q_st[1] * d, q_st[2] * d
    if u < phi_ex:
        r = flute_force_double_integral(k, du, dw, u)
        return r[0] - r0[0], r[1] - r0[1], r[2] - r0[2]
    d = u - phi_ex
    return r_ex[0] - r0[0] + q_ex[0] * d, r_ex[1] - r0[1] + q_ex[1] * d, r_ex[2] - r0[2] + q_ex[2] * d


@njit(cache=True)
def chip_arc(phi_st, phi_ex, du, dw):  # pragma: no cover - compiled
    """The part ``(lo, hi)`` (rad) of the engaged arc ``[phi_st, phi_ex]`` (within ``[0, pi]``)
    where the chip ``h = du sin(phi) + dw cos(phi)`` is positive: a tooth out of the cut takes
    no chip.  ``h = |d| sin(phi + beta)``, ``beta = atan2(dw, du)``, is positive on the half
    turn after ``b = -beta`` (mod 2 pi), which meets ``[0, pi]`` in one piece: ``[b, pi]`` if
    ``b <= pi``, else ``[0, b - pi]``.  ``hi <= lo``: no chip."""
    if du == 0.0 and dw == 0.0:
        return phi_st, phi_st
    b = (-math.atan2(dw, du)) % (2.0 * math.pi)
    if b <= math.pi:
        return max(phi_st, b), phi_ex
    return phi_st, min(phi_ex, b - math.pi)


@njit(cache=True)
def step_tool_forces_N(
    k, n_flutes, axial_depth_mm, chip_u, chip_w, phi_st, phi_ex, spindle_angle_rad, step_angle_rad, lag_rad
):  # pragma: no cover - compiled
    """Force on the tool, feed frame (N), averaged over one physics step, summed over the flutes.

    ``k`` is :meth:`CuttingCoefficients.as_array`.  Flute 0's tip turns from
    ``spindle_angle_rad`` through ``step_angle_rad`` (> 0) during the step; flute j trails it by
    ``2 pi j/N`` and cuts the chip ``h = chip_u[j] sin(phi) + chip_w[j] cos(phi)`` (mm; its
    chip vector in the feed frame, :func:`chip_arc`: only where h > 0; ``chip_u = c``,
    ``chip_w = 0``: the feed per tooth alone).  A helical flute's edge at height ``z`` above the
    bottom of the cut lags its tip by ``lag_rad z/a`` (``lag_rad = 2 a tan(helix)/D``; 0:
    straight flutes).  The average is exact for the step's chip vectors, so the force the twin
    applies carries the same impulse as the continuous model, whatever the timestep: straight
    flutes integrate :func:`flute_force_integral` over the engaged part of the step; helical
    ones integrate the flute's force ``a/lag [Q(clip(phi)) - Q(clip(phi - lag))]`` (at unit
    depth; the integral over the discs ``dz`` turned into one over their angles) once more, over
    the step (:func:`_clipped_double_integral`), the edge's whole turns (``lag`` over 2 pi)
    taken at once.
    """
    fx = fy = fz = 0.0
    two_pi = 2.0 * math.pi
    pitch = two_pi / n_flutes
    straight = lag_rad * n_flutes < 1e-6  # within 1 urad of lag per flute pitch
    per_rad = axial_depth_mm / lag_rad if not straight else 0.0  # depth per radian of lag (mm/rad)
    turns = math.floor(lag_rad / two_pi)
    rest = lag_rad - turns * two_pi
    scale = per_rad / step_angle_rad
    for j in range(n_flutes):
        du, dw = chip_u[j], chip_w[j]
        st, ex = chip_arc(phi_st, phi_ex, du, dw)
        if ex <= st:
            continue
        start = (spindle_angle_rad - j * pitch) % two_pi
        if straight:
            for shift in (0.0, -two_pi):  # the step may wrap past 2 pi into the next revolution
                lo = max(start + shift, st)
                hi = min(start + shift + step_angle_rad, ex)
                if hi > lo:
                    qh = flute_force_integral(k, axial_depth_mm, du, dw, hi)
                    ql = flute_force_integral(k, axial_depth_mm, du, dw, lo)
                    fx += (qh[0] - ql[0]) / step_angle_rad
                    fy += (qh[1] - ql[1]) / step_angle_rad
                    fz += (qh[2] - ql[2]) / step_angle_rad
            continue
        if turns > 0:  # each whole turn of the edge sweeps every angle once: the arc's whole force
            qh = flute_force_integral(k, 1.0, du, dw, ex)
            ql = flute_force_integral(k, 1.0, du, dw, st)
            whole = turns * per_rad
            fx, fy, fz = fx + whole * (qh[0] - ql[0]), fy + whole * (qh[1] - ql[1]), fz + whole * (qh[2] - ql[2])
        if rest <= 0.0:
            continue
        # the arc's copies one revolution apart that the swept angles [start - rest, start + step] meet
        first, last = math.floor((start - rest - ex) / two_pi), math.floor((start + step_angle_rad - st) / two_pi)
        if last < first:
            continue
        # the u below are within [u_lo, u_hi]: the latest copy's u - rest, the earliest's u + step
        u_lo, u_hi = (start - last * two_pi) - rest, (start - first * two_pi) + step_angle_rad
        ends = _arc_ends(k, du, dw, st, ex, u_lo, u_hi)
        for m in range(first, last + 1):
            u = start - m * two_pi
            g1 = _clipped_double_integral(k, du, dw, st, ex, ends, u + step_angle_rad)
            g0 = _clipped_double_integral(k, du, dw, st, ex, ends, u)
            h1 = _clipped_double_integral(k, du, dw, st, ex, ends, u + step_angle_rad - rest)
            h0 = _clipped_double_integral(k, du, dw, st, ex, ends, u - rest)
            fx += scale * (g1[0] - g0[0] - h1[0] + h0[0])
            fy += scale * (g1[1] - g0[1] - h1[1] + h0[1])
            fz += scale * (g1[2] - g0[2] - h1[2] + h0[2])
    return fx, fy, fz


def _window(start_s: float, stop_s: float | None, timestep_s: float = 0.0) -> tuple[float, float]:
    """``(lo, hi)``: the force acts on steps starting at ``lo <= t < hi``, that is
    ``start_s <= t < stop_s`` with half a step of slack for the rounding of the accumulated
    simulation time."""
    if not start_s >= 0:
        raise TwinInputError("start_s", start_s, "must be >= 0")
    if stop_s is not None and not stop_s > start_s:
        raise TwinInputError("stop_s", stop_s, f"must be > start_s = {start_s}")
    return start_s - 0.5 * timestep_s, math.inf if stop_s is None else stop_s - 0.5 * timestep_s


#: Slowest spindle (rev/min): one revolution a minute, a tooth period of at most 60 s.
MIN_SPINDLE_RPM = 1.0
#: Most flutes (or inserts) a cutter may have: the kernel loops over them every physics step;
#: large face mills carry a few dozen inserts, no milling cutter carries more than 100.
MAX_FLUTES = 100


def _check_cutter(spindle_rpm: float, n_flutes: int) -> None:
    """Spindle speed of at least :data:`MIN_SPINDLE_RPM` and a whole number of flutes from 1 to
    :data:`MAX_FLUTES`."""
    if not MIN_SPINDLE_RPM <= spindle_rpm < math.inf:
        raise TwinInputError("spindle_rpm", spindle_rpm, f"must be at least {MIN_SPINDLE_RPM:g} rev/min and finite")
    if int(n_flutes) != n_flutes or not 1 <= n_flutes <= MAX_FLUTES:
        raise TwinInputError("n_flutes", n_flutes, f"must be a whole number from 1 to {MAX_FLUTES}")


def _tooth_frequency_hz(spindle_rpm: float, n_flutes: int) -> float:
    """Tooth-passing frequency N rpm / 60 (Hz)."""
    return n_flutes * spindle_rpm / 60.0


def spindle_phase(phase_rad: float | None, seed: int) -> float:
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
    helix_deg : float
        Helix angle of the flutes (deg); 0: straight flutes.
    dynamics : ToolDynamicsSpec or None
        The tool's structure; with ``modes_in_run`` its modes vibrate in the run
        (:func:`mode_rows`) and its deflection enters the chip.
    """

    spindle_rpm: float
    n_flutes: int
    diameter_mm: float
    axial_depth_mm: float
    radial_depth_mm: float
    mode: str = "up"
    coefficients: CuttingCoefficients = MATERIALS[DEFAULT_MATERIAL].value.coefficients
    start_s: float = 0.0
    stop_s: float | None = None
    spindle_phase_rad: float | None = None
    seed: int = 0
    helix_deg: float = 0.0
    dynamics: ToolDynamicsSpec | None = None

    def __post_init__(self):
        _check_cutter(self.spindle_rpm, self.n_flutes)
        for name in ("diameter_mm", "axial_depth_mm"):
            if not getattr(self, name) > 0:
                raise TwinInputError(name, getattr(self, name), "must be > 0")
        if not 0.0 <= self.helix_deg < MAX_HELIX_DEG:
            raise TwinInputError("helix_deg", self.helix_deg, f"must be in [0, {MAX_HELIX_DEG})")
        immersion_angles(self.radial_depth_mm, self.diameter_mm, self.mode)
        _window(self.start_s, self.stop_s)

    @property
    def tooth_frequency_hz(self) -> float:
        """Tooth-passing frequency N rpm / 60 (Hz)."""
        return _tooth_frequency_hz(self.spindle_rpm, self.n_flutes)

    def kernel_arrays(self, machine) -> tuple[int, np.ndarray, np.ndarray]:
        """``(END_MILLING, params, state)`` for :func:`workpiece_forces`.

        The chip is regenerative (:func:`_chips`): where the tool is relative to the workpiece
        at the middle of the step less where it was when the last tooth to cut at the same angle
        passed (one tooth period back, or more where teeth left the cut), projected on the
        edge's normal, and none where that is negative.  The feed frame is the reference's
        (the planned feed direction, held through stops); the planned feed per tooth sets a
        Kienzle material's coefficients.  The state holds the step count, the feed direction,
        the last vibration and a ring buffer of the tool's positions (m).
        """
        phi_st, phi_ex = immersion_angles(self.radial_depth_mm, self.diameter_mm, self.mode)
        dt = machine.model.opt.timestep
        lag_steps = 1.0 / self.tooth_frequency_hz / dt
        n_hist = history_rows(lag_steps)
        lo, hi = _window(self.start_s, self.stop_s, dt)
        modes = mode_rows([self.dynamics], dt)
        jacobian = machine.workpiece_jacobian()
        params = pack_slots(
            END_MILLING_SLOTS,
            {
                **dict(zip(("K_tc", "K_rc", "K_ac", "K_te", "K_re", "K_ae", "mc"), self.coefficients.as_array())),
                "n_flutes": int(self.n_flutes),
                "axial_depth_mm": self.axial_depth_mm,
                "lag_rad": self.axial_depth_mm * helix_lag_rad_per_mm(self.helix_deg, self.diameter_mm),
                "phi_st": phi_st,
                "phi_ex": phi_ex,
                "omega": 2.0 * math.pi * self.spindle_rpm / 60.0,
                "phase0": spindle_phase(self.spindle_phase_rad, self.seed),
                "dt": dt,
                "lag_steps": lag_steps,
                "lo": lo,
                "hi": hi,
                "n_hist": n_hist,
                "n_jac": jacobian.size,
                "n_modes": len(modes),
            },
            jacobian,
        )
        state = chip_state(
            n_hist, (1.0, 0.0), len(modes), self.n_flutes
        )  # feed direction +x until the reference first moves
        return END_MILLING, np.concatenate([params, modes.ravel()]), state


@dataclass(frozen=True)
class AverageForce:
    """Choi 1999's average cutting force ``F = k_il v + k_c (z x v)`` on the workpiece (N).

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
            raise TwinInputError(
                "harmonic_fraction",
                self.harmonic_fraction,
                "must be in [0, 0.2]: Choi 1999 bounds the cyclic part at 20 % of the average",
            )
        _check_cutter(self.spindle_rpm, self.n_flutes)
        _window(self.start_s, self.stop_s)

    def kernel_arrays(self, machine) -> tuple[int, np.ndarray, np.ndarray]:
        """``(AVERAGE_FORCE, params, state)`` for :func:`workpiece_forces`."""
        lo, hi = _window(self.start_s, self.stop_s, machine.model.opt.timestep)
        params = pack_slots(
            AVERAGE_FORCE_SLOTS,
            {
                "k_il": self.k_il_N_s_per_m,
                "k_c": self.k_c_N_s_per_m,
                "harmonic_fraction": self.harmonic_fraction,
                "omega": 2.0 * math.pi * _tooth_frequency_hz(self.spindle_rpm, self.n_flutes),
                "phase": spindle_phase(self.harmonic_phase_rad, self.seed),
                "lo": lo,
                "hi": hi,
            },
            machine.workpiece_jacobian(),
        )
        return AVERAGE_FORCE, params, np.zeros(0)


#: Kinds of :func:`workpiece_forces`.
END_MILLING, AVERAGE_FORCE, PROGRAM_MILLING = 0, 1, 2
#: The parameter slots of each force kernel, in order: the one declaration of its layout.  The
#: workpiece's 2 x nq position Jacobian follows them (:func:`pack_slots`), then an end
#: milling's ``n_modes`` tool modes (:data:`MODE_COLUMNS`).
END_MILLING_SLOTS = (
    "K_tc",
    "K_rc",
    "K_ac",
    "K_te",
    "K_re",
    "K_ae",
    "mc",
    "n_flutes",
    "axial_depth_mm",
    "lag_rad",
    "phi_st",
    "phi_ex",
    "omega",
    "phase0",
    "dt",
    "lag_steps",
    "lo",
    "hi",
    "n_hist",
    "n_jac",
    "n_modes",
)
AVERAGE_FORCE_SLOTS = ("k_il", "k_c", "harmonic_fraction", "omega", "phase", "lo", "hi")
#: A part program's milling (:class:`twin.machining.program_cut.ProgramMilling`): then the workpiece
#: Jacobian (2 x nq), each tool's :data:`PM_TOOL_COLUMNS`, the tools' ``n_modes`` modes
#: (:data:`MODE_COLUMNS`) and the engagement table of ``n_table`` rows of :data:`PM_COLUMNS`,
#: one every ``table_period`` seconds.
PROGRAM_MILLING_SLOTS = ("n_tools", "table_period", "n_table", "dt", "n_hist", "n_jac", "n_modes")
#: A tool's values: its coefficients (:meth:`CuttingCoefficients.as_array`), flutes and helix lag
#: per depth (:func:`helix_lag_rad_per_mm`).
PM_TOOL_COLUMNS = ("K_tc", "K_rc", "K_ac", "K_te", "K_re", "K_ae", "mc", "n_flutes", "lag_rad_per_mm")
#: The table's columns: the two engaged arcs (rad) each with its mean axial depth (mm), spindle
#: speed (rad/s), spindle angle at the row's start (rad), tool index.
PM_COLUMNS = ("phi_st1", "phi_ex1", "depth1_mm", "phi_st2", "phi_ex2", "depth2_mm", "omega", "angle", "tool")
_PM = {name: i for i, name in enumerate(PROGRAM_MILLING_SLOTS)}
PM_N_TOOLS, PM_PERIOD, PM_N_TABLE, PM_DT = _PM["n_tools"], _PM["table_period"], _PM["n_table"], _PM["dt"]
PM_N_HIST, PM_N_JAC, PM_JACOBIAN, PM_WIDTH = _PM["n_hist"], _PM["n_jac"], len(PROGRAM_MILLING_SLOTS), len(PM_COLUMNS)
PM_N_MODES = _PM["n_modes"]
PM_TOOL_WIDTH, PM_TOOL_FLUTES = len(PM_TOOL_COLUMNS), PM_TOOL_COLUMNS.index("n_flutes")
PM_TOOL_LAG = PM_TOOL_COLUMNS.index("lag_rad_per_mm")
PM_TOOL_K_FIRST, PM_TOOL_K_END = PM_TOOL_COLUMNS.index("K_tc"), PM_TOOL_COLUMNS.index("mc") + 1
PM_PHI_ST1, PM_PHI_EX1, PM_DEPTH1 = (
    PM_COLUMNS.index("phi_st1"),
    PM_COLUMNS.index("phi_ex1"),
    PM_COLUMNS.index("depth1_mm"),
)
PM_DEPTH2, PM_OMEGA = PM_COLUMNS.index("depth2_mm"), PM_COLUMNS.index("omega")
PM_ANGLE, PM_TOOL = PM_COLUMNS.index("angle"), PM_COLUMNS.index("tool")
#: Columns from one engaged arc's to the next's (phi_st1 to phi_st2).
PM_ARC_STRIDE = PM_COLUMNS.index("phi_st2") - PM_PHI_ST1
#: A milling kernel's state: the step count, the feed direction held through stops and the last
#: once-per-tooth difference of the vibration (feed frame, mm; :func:`_probe`), then each tool
#: mode's displacement and velocity, the step's scratch (:func:`_scratch`) and the ring buffer of
#: the tool's XY position relative to the workpiece (:func:`_record_position`).
CHIP_STATE = ("steps", "feed_x", "feed_y", "vib_u", "vib_w")
CHIP_STEPS, CHIP_FEED_X, CHIP_FEED_Y, CHIP_VIB_U, CHIP_VIB_W = (CHIP_STATE.index(name) for name in CHIP_STATE)
CHIP_HISTORY = len(CHIP_STATE)
#: Earlier tooth passes a chip is measured against (multiple regeneration): the surface at a
#: tooth's angle is the one the last of them to cut there left.  Three passes let a strong
#: chatter recut material that older passes had removed, and grow without bound (the
#: Insperger-Stepan benchmark at five times its critical depth); twelve keep it bounded there
#: and at nine times.
REGENERATIONS = 12
#: Rows of a milling kernel's position history at most (32 MB): a spindle so slow that
#: :data:`REGENERATIONS` tooth periods do not fit keeps as many as do (one at least).
MAX_HISTORY_ROWS = 2_000_000
#: What the milling kernels add up over each physics step that cuts, for the chatter indicator
#: (:mod:`twin.machining.chatter`): the steps, the squares of the once-per-tooth difference of
#: the vibration along and across the feed (mm^2), its sign changes along and across, and the
#: square of the planned feed per tooth (mm^2).
PROBE = ("cut_steps", "vib_u2", "vib_w2", "crossings_u", "crossings_w", "feed2")
PROBE_STEPS, PROBE_U2, PROBE_W2, PROBE_CROSS_U, PROBE_CROSS_W, PROBE_FEED2 = (PROBE.index(name) for name in PROBE)
#: A tool mode in a milling kernel's parameters (:func:`mode_rows`): the tool it is of (index),
#: the direction it vibrates along (unit vector, machine X/Y), and its exact discretization over
#: one physics step under the step's force held: ``[q, v]' = Phi [q, v] + Gamma F``.
MODE_COLUMNS = ("tool", "dir_x", "dir_y", "phi_qq", "phi_qv", "phi_vq", "phi_vv", "gamma_q", "gamma_v")
MODE_TOOL, MODE_DIR_X, MODE_DIR_Y, MODE_PHI_QQ, MODE_PHI_QV, MODE_PHI_VQ, MODE_PHI_VV, MODE_GAMMA_Q, MODE_GAMMA_V = (
    MODE_COLUMNS.index(name) for name in MODE_COLUMNS
)
MODE_WIDTH = len(MODE_COLUMNS)
#: Physics steps per period of a tool's highest mode at least, where its modes are in the run:
#: the chip is sampled once a step.  On the Insperger-Stepan benchmark the twin's critical depth
#: fell short of the semi-discretization's by 3.5-5.4 % at 10 steps a period, 0.7-1.6 % at 22,
#: 0.2 % at 54 (10 000 and 20 000 rpm).
MIN_STEPS_PER_MODE_PERIOD = 20
#: Columns of :func:`workpiece_forces`'s ``fops``: each model's kind and where its parameters and
#: state lie in ``fpar`` and ``fstate``.
FORCE_OP_COLUMNS = ("kind", "par_start", "par_len", "state_start", "state_len")
FORCE_KIND, FORCE_PAR_START, FORCE_PAR_LEN, FORCE_STATE_START, FORCE_STATE_LEN = (
    FORCE_OP_COLUMNS.index(name) for name in FORCE_OP_COLUMNS
)


def history_rows(tooth_period_steps: float) -> int:
    """Rows of a milling kernel's position ring buffer: :data:`REGENERATIONS` tooth periods
    (physics steps) within :data:`MAX_HISTORY_ROWS` (one period at least), and two to
    interpolate in."""
    return min(int(REGENERATIONS * tooth_period_steps), max(MAX_HISTORY_ROWS, int(tooth_period_steps))) + 2


def mode_rows(dynamics, timestep_s: float) -> np.ndarray:
    """The tool modes of a milling kernel (:data:`MODE_COLUMNS`), shape (n, MODE_WIDTH).

    Each mode ``q'' + 2 zeta w q' + w^2 q = F/m`` (``F`` the cutting force on the tool along
    its direction, N) is discretized exactly over the physics step ``dt`` for a force held over
    it (the kernel's force is the step's mean): ``Phi = e^(A dt)``, ``Gamma = int_0^dt e^(A s) B
    ds``, both from the exponential of the augmented matrix ``[[A, B], [0, 0]] dt``.

    Parameters
    ----------
    dynamics : sequence of ToolDynamicsSpec or None
        Each tool's; those without ``modes_in_run`` have no rows.
    timestep_s : float

    Raises
    ------
    TwinInputError
        A mode the step does not resolve (:data:`MIN_STEPS_PER_MODE_PERIOD`).
    """
    from scipy.linalg import expm

    rows = []
    for tool, spec in enumerate(dynamics):
        if spec is None or not spec.modes_in_run:
            continue
        for mode in spec.modes:
            if mode.frequency_hz * timestep_s * MIN_STEPS_PER_MODE_PERIOD > 1.0:
                most = 1.0 / (MIN_STEPS_PER_MODE_PERIOD * mode.frequency_hz)
                raise TwinInputError(
                    "timestep_s",
                    timestep_s,
                    f"the tool's {mode.frequency_hz:g} Hz mode in the run needs "
                    f"{MIN_STEPS_PER_MODE_PERIOD} steps a period: at most {most:.3g} s",
                )
            w, zeta = mode.omega_rad_s, mode.damping_ratio
            augmented = np.zeros((3, 3))
            augmented[:2, :2] = [[0.0, 1.0], [-(w**2), -2.0 * zeta * w]]
            augmented[1, 2] = 1.0 / mode.mass
            step = expm(augmented * timestep_s)
            direction = (1.0, 0.0) if mode.direction == "x" else (0.0, 1.0)
            rows.append([tool, *direction, *step[:2, :2].ravel(), *step[:2, 2]])
    return np.array(rows, float).reshape(-1, MODE_WIDTH)


@njit(cache=True, inline="always")
def _tool_deflection(modes, mstate, tool, dt):  # pragma: no cover - compiled
    """The tool tip's deflection (m, machine X/Y) at the middle of the step: the modes of
    ``tool`` at ``q + v dt/2`` (``modes``: :data:`MODE_COLUMNS` row after row, flat; ``mstate``:
    each mode's ``q``, ``v``)."""
    dx = dy = 0.0
    for r in range(modes.shape[0] // MODE_WIDTH):
        mode = r * MODE_WIDTH
        if int(modes[mode + MODE_TOOL]) == tool:
            q = mstate[2 * r] + 0.5 * dt * mstate[2 * r + 1]
            dx += modes[mode + MODE_DIR_X] * q
            dy += modes[mode + MODE_DIR_Y] * q
    return dx, dy


@njit(cache=True, inline="always")
def _advance_modes(modes, mstate, tool, fx, fy):  # pragma: no cover - compiled
    """Advance the modes of ``tool`` over the step under the force ``(fx, fy)`` on the tool
    (N, machine X/Y, held over the step): the exact discretization of :func:`mode_rows` (``modes``
    flat, as :func:`_tool_deflection`'s)."""
    for r in range(modes.shape[0] // MODE_WIDTH):
        mode = r * MODE_WIDTH
        if int(modes[mode + MODE_TOOL]) == tool:
            f = fx * modes[mode + MODE_DIR_X] + fy * modes[mode + MODE_DIR_Y]
            q, v = mstate[2 * r], mstate[2 * r + 1]
            mstate[2 * r] = (
                modes[mode + MODE_PHI_QQ] * q + modes[mode + MODE_PHI_QV] * v + modes[mode + MODE_GAMMA_Q] * f
            )
            mstate[2 * r + 1] = (
                modes[mode + MODE_PHI_VQ] * q + modes[mode + MODE_PHI_VV] * v + modes[mode + MODE_GAMMA_V] * f
            )


def chip_state(n_hist: int, feed_direction: tuple[float, float], n_modes: int = 0, n_flutes: int = 1) -> np.ndarray:
    """A milling kernel's initial state (:data:`CHIP_STATE`, each tool mode's displacement and
    velocity at rest, the scratch of a step of up to ``n_flutes`` flutes (:func:`_scratch`), then
    a ring buffer of ``n_hist`` XY positions), with the feed direction held until the reference
    first moves (a unit vector, or zero: no force until then)."""
    state = np.zeros(CHIP_HISTORY + 2 * n_modes + 2 * REGENERATIONS + 2 * n_flutes + 2 * n_hist)
    state[CHIP_FEED_X], state[CHIP_FEED_Y] = feed_direction
    return state


@njit(cache=True, inline="always")
def _scratch(state, n_modes, n_flutes):  # pragma: no cover - compiled
    """The scratch of one step in a milling kernel's ``state`` (:func:`chip_state`), which no
    step reads before it writes it (kept in the state so that the kernels allocate nothing):
    each earlier tooth pass's chip vector (:data:`REGENERATIONS` pairs, flat) and the flutes' chip
    vectors, along and across the feed (``n_flutes`` each) (:func:`_chips`).  The kernels index
    their arrays flat (no ``reshape``, which costs a call into numba's C helpers a step)."""
    first = CHIP_HISTORY + 2 * n_modes
    passes = state[first : first + 2 * REGENERATIONS]
    chips = first + 2 * REGENERATIONS
    return passes, state[chips : chips + n_flutes], state[chips + n_flutes : chips + 2 * n_flutes]


_EM = {name: i for i, name in enumerate(END_MILLING_SLOTS)}
_AF = {name: i for i, name in enumerate(AVERAGE_FORCE_SLOTS)}
# the kernels' slot indices (module constants: numba freezes them)
EM_K, EM_N_FLUTES, EM_DEPTH, EM_LAG, EM_PHI_ST, EM_PHI_EX = (
    _EM["K_tc"],
    _EM["n_flutes"],
    _EM["axial_depth_mm"],
    _EM["lag_rad"],
    _EM["phi_st"],
    _EM["phi_ex"],
)
EM_OMEGA, EM_PHASE0, EM_DT, EM_LAG_STEPS = _EM["omega"], _EM["phase0"], _EM["dt"], _EM["lag_steps"]
EM_LO, EM_HI, EM_N_HIST, EM_JACOBIAN = _EM["lo"], _EM["hi"], _EM["n_hist"], len(END_MILLING_SLOTS)
EM_N_JAC, EM_N_MODES = _EM["n_jac"], _EM["n_modes"]
EM_K_END = _EM["mc"] + 1
AF_K_IL, AF_K_C, AF_R, AF_OMEGA = _AF["k_il"], _AF["k_c"], _AF["harmonic_fraction"], _AF["omega"]
AF_PHASE, AF_LO, AF_HI, AF_JACOBIAN = _AF["phase"], _AF["lo"], _AF["hi"], len(AVERAGE_FORCE_SLOTS)


def pack_slots(slots: tuple[str, ...], values: dict[str, float], jacobian: np.ndarray) -> np.ndarray:
    """A force kernel's parameter array: ``values`` in the order of ``slots`` (every slot
    given, no other), then the workpiece Jacobian row by row."""
    if set(values) != set(slots):
        raise ValueError(f"parameter slots {sorted(set(slots) ^ set(values))} missing or unknown")
    return np.concatenate([[float(values[name]) for name in slots], np.asarray(jacobian, float).ravel()])


@njit(cache=True, inline="always")
def _record_position(jac, qpos, qvel, dt, state, n, tool_xy):  # pragma: no cover - compiled
    """Step count (``state``'s :data:`CHIP_STEPS`) on by one and the tool's XY position
    relative to the workpiece at the middle of the step, ``tool_xy - jac @ (qpos + qvel dt/2)``
    (m; the spindle stands still in the world, its tip deflected by ``tool_xy``), into the ring
    buffer of the last ``2 n`` entries of ``state`` (filled with it at the first step; position
    ``m`` at ``2 m``, ``2 m + 1``); ``jac`` is flat, row by row.  Returns the step index and the
    buffer."""
    hist = state[state.shape[0] - 2 * n :]
    i = int(state[CHIP_STEPS])
    state[CHIP_STEPS] = i + 1
    cols = jac.shape[0] // 2
    for r in range(2):
        acc = tool_xy[r]
        for j in range(cols):
            acc -= jac[r * cols + j] * (qpos[j] + 0.5 * dt * qvel[j])
        hist[2 * (i % n) + r] = acc
    if i == 0:
        for m in range(1, n):
            hist[2 * m], hist[2 * m + 1] = hist[0], hist[1]
    return i, hist


@njit(cache=True, inline="always")
def _feed_frame(feed_velocity, state):  # pragma: no cover - compiled
    """The planned feed: the tool's speed relative to the workpiece (m/s, the reference's:
    ``-feed_velocity``, the workpiece's planned velocity) and its direction, held in ``state``
    (:data:`CHIP_FEED_X`, :data:`CHIP_FEED_Y`) through stops."""
    vx, vy = -feed_velocity[0], -feed_velocity[1]
    speed = math.hypot(vx, vy)
    if speed > MIN_FEED_M_PER_S:
        state[CHIP_FEED_X], state[CHIP_FEED_Y] = vx / speed, vy / speed
    return speed, state[CHIP_FEED_X], state[CHIP_FEED_Y]


@njit(cache=True, inline="always")
def _past(hist, i, n, lag):  # pragma: no cover - compiled
    """The buffer's position ``lag`` (> 0, fractional) steps before step ``i`` (linear
    interpolation; the first recorded position before it)."""
    lo = int(lag)
    frac = lag - lo
    p0, p1 = 2 * (max(i - lo, 0) % n), 2 * (max(i - lo - 1, 0) % n)
    return (1.0 - frac) * hist[p0] + frac * hist[p1], (1.0 - frac) * hist[p0 + 1] + frac * hist[p1 + 1]


@njit(cache=True, inline="always")
def _chips(hist, i, n, lag_steps, ux, uy, angle, n_flutes, passes_uw, chip_u, chip_w):  # pragma: no cover - compiled
    """Each flute's chip vector (feed frame, mm) into ``chip_u``, ``chip_w``: where the tool is
    now less where it was when the last earlier tooth to cut at this flute's angle ``angle - 2 pi
    j/N`` (rad) passed it, ``m`` tooth periods (``lag_steps`` physics steps each) ago, ``m``
    from 1 to :data:`REGENERATIONS` (those the buffer of ``n`` rows holds) the one that leaves
    the thinnest chip there (multiple regeneration: a tooth that left the cut left the surface
    before it).  Its projection on the edge's normal is the chip thickness
    (:func:`step_tool_forces_N`).  The tool's motion over each of the ``m`` tooth periods, the
    same for every flute, goes into ``passes_uw`` (at ``2 (m - 1)``, ``2 m - 1``; ``hist`` flat as
    :func:`_record_position`'s).  Returns the tool's motion over the last tooth period, feed
    frame (mm)."""
    px, py = hist[2 * (i % n)], hist[2 * (i % n) + 1]
    pitch = 2.0 * math.pi / n_flutes
    passes = max(1, min(REGENERATIONS, int((n - 2) / lag_steps)))  # those the buffer holds
    for m in range(1, passes + 1):
        qx, qy = _past(hist, i, n, m * lag_steps)
        dx, dy = (px - qx) * 1e3, (py - qy) * 1e3
        passes_uw[2 * m - 2] = dx * ux + dy * uy  # along the feed
        passes_uw[2 * m - 1] = dy * ux - dx * uy  # along z x feed
    for j in range(n_flutes):
        s, c = math.sin(angle - j * pitch), math.cos(angle - j * pitch)
        best = math.inf
        for m in range(passes):
            du, dw = passes_uw[2 * m], passes_uw[2 * m + 1]
            h = du * s + dw * c
            if h < best:
                best, chip_u[j], chip_w[j] = h, du, dw
    return passes_uw[0], passes_uw[1]


@njit(cache=True, inline="always")
def _probe(state, du, dw, feed_mm, probe):  # pragma: no cover - compiled
    """Add one cutting step to ``probe`` (:data:`PROBE`): the once-per-tooth difference of the
    vibration, ``(du - feed_mm, dw)`` (mm: the chip vector one tooth period back less the planned
    feed per tooth), its squares and sign changes since the last cutting step (kept in
    ``state``)."""
    vu, vw = du - feed_mm, dw
    probe[PROBE_STEPS] += 1.0
    probe[PROBE_U2] += vu * vu
    probe[PROBE_W2] += vw * vw
    probe[PROBE_CROSS_U] += 1.0 if vu * state[CHIP_VIB_U] < 0.0 else 0.0
    probe[PROBE_CROSS_W] += 1.0 if vw * state[CHIP_VIB_W] < 0.0 else 0.0
    probe[PROBE_FEED2] += feed_mm * feed_mm
    state[CHIP_VIB_U], state[CHIP_VIB_W] = vu, vw


@njit(cache=True, inline="always")
def _end_milling(par, state, qpos, qvel, feed_velocity, t, out, probe):  # pragma: no cover - compiled
    """Add one step's mechanistic milling force on the workpiece (world frame, N) to ``out``
    and the step's vibration to ``probe``; advance the tool's modes under its reaction."""
    k = par[EM_K:EM_K_END]
    n_flutes, a, lag, phi_st, phi_ex = int(par[EM_N_FLUTES]), par[EM_DEPTH], par[EM_LAG], par[EM_PHI_ST], par[EM_PHI_EX]
    omega, phase0, dt, lag_steps = par[EM_OMEGA], par[EM_PHASE0], par[EM_DT], par[EM_LAG_STEPS]
    lo, hi, n, n_jac, n_modes = par[EM_LO], par[EM_HI], int(par[EM_N_HIST]), int(par[EM_N_JAC]), int(par[EM_N_MODES])
    modes = par[EM_JACOBIAN + n_jac :]
    mstate = state[CHIP_HISTORY : CHIP_HISTORY + 2 * n_modes]
    tool_xy = _tool_deflection(modes, mstate, 0, dt)
    i, hist = _record_position(par[EM_JACOBIAN : EM_JACOBIAN + n_jac], qpos, qvel, dt, state, n, tool_xy)
    speed, ux, uy = _feed_frame(feed_velocity, state)
    fx = fy = fz = 0.0
    if lo <= t < hi:
        feed_mm = speed * lag_steps * dt * 1e3
        angle = phase0 + omega * t
        passes_uw, chip_u, chip_w = _scratch(state, n_modes, n_flutes)
        mid = angle + 0.5 * omega * dt - 0.5 * lag
        du, dw = _chips(hist, i, n, lag_steps, ux, uy, mid, n_flutes, passes_uw, chip_u, chip_w)
        _probe(state, du, dw, feed_mm, probe)
        k = kienzle_coefficients(k, feed_mm, phi_st, phi_ex)
        fx, fy, fz = step_tool_forces_N(k, n_flutes, a, chip_u, chip_w, phi_st, phi_ex, angle, omega * dt, lag)
    _apply(fx, fy, fz, ux, uy, modes, mstate, 0, out)


@njit(cache=True, inline="always")
def _apply(fx, fy, fz, ux, uy, modes, mstate, tool, out):  # pragma: no cover - compiled
    """The step's force on the tool (feed frame, N): its reaction onto the workpiece (``out``,
    world frame), the force itself onto the modes of ``tool``."""
    wx, wy = fx * ux - fy * uy, fx * uy + fy * ux  # the force on the tool, world frame
    out[0] -= wx
    out[1] -= wy
    out[2] -= fz
    _advance_modes(modes, mstate, tool, wx, wy)


@njit(cache=True, inline="always")
def _program_milling(par, state, qpos, qvel, feed_velocity, t, out, probe):  # pragma: no cover - compiled
    """Add one step's milling force of a part program on the workpiece (world frame, N) to
    ``out`` and its vibration to ``probe``: the engagement, spindle and tool by time from the
    table, the chip regenerated from the tool's motion relative to the workpiece (as
    :func:`_end_milling`)."""
    n_tools, period, n_table = int(par[PM_N_TOOLS]), par[PM_PERIOD], int(par[PM_N_TABLE])
    dt, n, n_jac, n_modes = par[PM_DT], int(par[PM_N_HIST]), int(par[PM_N_JAC]), int(par[PM_N_MODES])
    jac = par[PM_JACOBIAN : PM_JACOBIAN + n_jac]
    tools_start = PM_JACOBIAN + n_jac
    tools_end = tools_start + PM_TOOL_WIDTH * n_tools
    modes_end = tools_end + MODE_WIDTH * n_modes
    modes = par[tools_end:modes_end]
    mstate = state[CHIP_HISTORY : CHIP_HISTORY + 2 * n_modes]
    row = min(max(int(t / period), 0), n_table - 1)
    entry = par[modes_end + row * PM_WIDTH : modes_end + (row + 1) * PM_WIDTH]  # the table's row
    tool = int(entry[PM_TOOL])
    i, hist = _record_position(jac, qpos, qvel, dt, state, n, _tool_deflection(modes, mstate, tool, dt))
    speed, ux, uy = _feed_frame(feed_velocity, state)
    omega = entry[PM_OMEGA]
    if (entry[PM_DEPTH1] <= 0.0 and entry[PM_DEPTH2] <= 0.0) or omega <= 0.0 or ux == uy == 0.0:
        _advance_modes(modes, mstate, tool, 0.0, 0.0)
        return
    values = par[tools_start + PM_TOOL_WIDTH * tool : tools_start + PM_TOOL_WIDTH * (tool + 1)]  # the tool's
    k = values[PM_TOOL_K_FIRST:PM_TOOL_K_END]
    n_flutes, lag_per_mm = int(values[PM_TOOL_FLUTES]), values[PM_TOOL_LAG]
    lag_steps = 2.0 * math.pi / (omega * n_flutes) / dt
    feed_mm = speed * lag_steps * dt * 1e3
    angle = entry[PM_ANGLE] + omega * (t - row * period)
    passes_uw, chip_u, chip_w = _scratch(state, n_modes, n_flutes)
    depth = max(entry[PM_DEPTH1], entry[PM_DEPTH2])
    mid = angle + 0.5 * omega * dt - 0.5 * depth * lag_per_mm
    du, dw = _chips(hist, i, n, lag_steps, ux, uy, mid, n_flutes, passes_uw, chip_u, chip_w)
    _probe(state, du, dw, feed_mm, probe)
    fx = fy = fz = 0.0
    for arc in range(2):
        first = PM_ARC_STRIDE * arc
        st, ex = entry[PM_PHI_ST1 + first], entry[PM_PHI_EX1 + first]
        a = entry[PM_DEPTH1 + first]
        if ex > st and a > 0.0:
            ka = kienzle_coefficients(k, feed_mm, st, ex)
            gx, gy, gz = step_tool_forces_N(ka, n_flutes, a, chip_u, chip_w, st, ex, angle, omega * dt, a * lag_per_mm)
            fx, fy, fz = fx + gx, fy + gy, fz + gz
    _apply(fx, fy, fz, ux, uy, modes, mstate, tool, out)


@njit(cache=True, inline="always")
def _average_force(par, qvel, t, out):  # pragma: no cover - compiled
    """Add Choi 1999's average cutting force on the workpiece (N) to ``out``."""
    k_il, k_c, r, w = par[AF_K_IL], par[AF_K_C], par[AF_R], par[AF_OMEGA]
    phase, lo, hi = par[AF_PHASE], par[AF_LO], par[AF_HI]
    if not (lo <= t < hi):
        return
    jac = par[AF_JACOBIAN:]  # row by row
    cols = jac.shape[0] // 2
    vx = vy = 0.0
    for j in range(cols):
        vx += jac[j] * qvel[j]
        vy += jac[cols + j] * qvel[j]
    gain = 1.0 + r * math.sin(w * t + phase) if r else 1.0
    out[0] += gain * (k_il * vx - k_c * vy)
    out[1] += gain * (k_il * vy + k_c * vx)


@njit(cache=True)
def workpiece_forces(fops, fpar, fstate, qpos, qvel, feed_velocity, t, xfrc, body, f_sum, probe):  # pragma: no cover
    """Write the summed force of every model on the workpiece for the physics step starting at
    time ``t`` (s) into ``xfrc[body, :3]`` (N, world frame) and add it to ``f_sum`` (3,);
    ``feed_velocity`` (2,) is the workpiece's planned XY velocity (m/s, the reference's), which
    sets the feed frame; the milling models add the step's vibration to ``probe``
    (:data:`PROBE`).  ``fops`` rows: :data:`FORCE_OP_COLUMNS`."""
    out = xfrc[body, :3]  # the models add into it (a view: no array allocated a step)
    out[:] = 0.0
    for m in range(fops.shape[0]):
        kind, p0, pn = fops[m, FORCE_KIND], fops[m, FORCE_PAR_START], fops[m, FORCE_PAR_LEN]
        s0, sn = fops[m, FORCE_STATE_START], fops[m, FORCE_STATE_LEN]
        if kind == END_MILLING:
            _end_milling(fpar[p0 : p0 + pn], fstate[s0 : s0 + sn], qpos, qvel, feed_velocity, t, out, probe)
        elif kind == PROGRAM_MILLING:
            _program_milling(fpar[p0 : p0 + pn], fstate[s0 : s0 + sn], qpos, qvel, feed_velocity, t, out, probe)
        else:
            _average_force(fpar[p0 : p0 + pn], qvel, t, out)
    for i in range(3):
        f_sum[i] += out[i]


class ForceModels:
    """Force models on the workpiece packed for :func:`workpiece_forces`: one run's arrays.

    Parameters
    ----------
    models : sequence of EndMilling or AverageForce
    machine : BuiltMachine
    """

    def __init__(self, models, machine):
        rows, pars, states = [], [], []
        p0 = s0 = 0
        for m in models:
            kind, par, state = m.kernel_arrays(machine)
            columns = {"kind": kind, "par_start": p0, "par_len": len(par), "state_start": s0, "state_len": len(state)}
            rows.append([columns[name] for name in FORCE_OP_COLUMNS])
            pars.append(par)
            states.append(state)
            p0, s0 = p0 + len(par), s0 + len(state)
        self.fops = np.array(rows, np.int64).reshape(-1, len(FORCE_OP_COLUMNS))
        self.fpar = np.concatenate(pars) if pars else np.zeros(0)
        self.fstate = np.concatenate(states) if states else np.zeros(0)

    def __len__(self) -> int:
        return len(self.fops)

    def force_N(self, qpos, qvel, t: float, feed_velocity=(0.0, 0.0)) -> np.ndarray:
        """:func:`workpiece_forces` of these models for one step starting at ``t`` (s), the
        workpiece planned to move at ``feed_velocity`` (m/s): the force on the workpiece (N,
        world frame), shape (3,)."""
        xfrc, total = np.zeros((1, 6)), np.zeros(3)
        velocity = np.asarray(feed_velocity, float)
        workpiece_forces(
            self.fops, self.fpar, self.fstate, qpos, qvel, velocity, t, xfrc, 0, total, np.zeros(len(PROBE))
        )
        return total


#: A cutting coefficient's magnitude at most (N/mm^2): twice hardened steel's kc1 (about 5 000).
MAX_CUTTING_N_PER_MM2 = 10_000.0
#: An edge coefficient's magnitude at most (N/mm): ten times the largest measured (tens of N/mm).
MAX_EDGE_N_PER_MM = 1_000.0


class CoefficientsSpec(StrictSpec):
    """Overrides of the material's coefficients: linear cutting (N/mm^2) and edge (N/mm) ones,
    or the Kienzle form ``kc1_N_per_mm2`` with ``mc`` (radial and axial then our ratios of it,
    :data:`~twin.machining.materials.KIENZLE_RADIAL_RATIO`, unless ``K_rc``, ``K_ac`` are given:
    at h = 1 mm)."""

    # the chip is sheared against the cut: the tangential cutting and edge forces oppose the
    # cutting speed (positive); hardened steels' kc1 are about 5 000 N/mm^2 and edge forces tens
    # of N/mm, so a magnitude twice that (MAX_CUTTING_N_PER_MM2, MAX_EDGE_N_PER_MM) is no material
    K_tc: float | None = Field(None, gt=0, le=MAX_CUTTING_N_PER_MM2, description="tangential cutting, N/mm^2")
    K_rc: float | None = Field(None, ge=-MAX_CUTTING_N_PER_MM2, le=MAX_CUTTING_N_PER_MM2, description="N/mm^2")
    K_ac: float | None = Field(None, ge=-MAX_CUTTING_N_PER_MM2, le=MAX_CUTTING_N_PER_MM2, description="N/mm^2")
    K_te: float | None = Field(None, ge=0, le=MAX_EDGE_N_PER_MM, description="tangential edge (rubbing), N/mm")
    K_re: float | None = Field(None, ge=-MAX_EDGE_N_PER_MM, le=MAX_EDGE_N_PER_MM, description="N/mm")
    K_ae: float | None = Field(None, ge=-MAX_EDGE_N_PER_MM, le=MAX_EDGE_N_PER_MM, description="N/mm")
    kc1_N_per_mm2: float | None = Field(
        None,
        gt=0,
        le=MAX_CUTTING_N_PER_MM2,
        description="Kienzle: specific cutting force at h = 1 mm, N/mm^2 (give mc with it)",
    )
    mc: float | None = Field(None, ge=0, lt=1, description="Kienzle exponent, kc = kc1 h^-mc (give kc1_N_per_mm2)")

    @model_validator(mode="after")
    def _kienzle_form(self):
        if self.kc1_N_per_mm2 is not None and self.mc is None:
            raise ValueError("kc1_N_per_mm2 needs mc (the Kienzle exponent, 0 <= mc < 1) beside it")
        if self.mc is not None and self.kc1_N_per_mm2 is None:
            raise ValueError("mc needs kc1_N_per_mm2 (N/mm^2 at h = 1 mm) beside it")
        if self.kc1_N_per_mm2 is not None and self.K_tc is not None:
            raise ValueError("give kc1_N_per_mm2 (Kienzle) or K_tc (linear), not both")
        return self

    def applied_to(self, material: str) -> CuttingCoefficients:
        """The coefficients of ``material`` (:data:`~twin.machining.materials.MATERIALS`) with the
        ones given here in their place; a Kienzle form given replaces the material's whole."""
        given = self.model_dump(exclude_none=True)
        kc1 = given.pop("kc1_N_per_mm2", None)
        base = MATERIALS[material].value.coefficients if kc1 is None else kienzle(kc1, given.pop("mc"))
        return replace(base, **given)


class WorkMaterialSpec(StrictSpec):
    """What a cutter cuts: the ``material`` (its coefficients from
    :data:`~twin.machining.materials.MATERIALS`) and the user's ``coefficients`` over them; a
    ``[tool]``, a ``[[tools]]`` entry and an ``end_milling`` disturbance have both."""

    # the names of the materials table (pydantic evaluates the Literal at run time; mypy cannot)
    material: Literal[tuple(MATERIALS)] = Field(  # type: ignore[valid-type]
        DEFAULT_MATERIAL, description="cutting coefficients of: " + ", ".join(MATERIALS)
    )
    coefficients: CoefficientsSpec = Field(
        default_factory=CoefficientsSpec, description="the user's own coefficients, over the material's"
    )

    def cutting_coefficients(self) -> CuttingCoefficients:
        """The material's coefficients with the user's given ones in their place."""
        return self.coefficients.applied_to(self.material)
