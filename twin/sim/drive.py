"""Drive and sensor models between the controller and MuJoCo, and their per-tick kernels.

Drive: an input disturbance (V), saturation of the control input (V) and a transport delay
realized at the physics timestep (a whole number of steps), held in its own delay buffer.
Sensors: encoder quantization (resolution in m), Gaussian measurement noise from a seeded
generator, and a velocity measurement (backward difference of the encoder, or an ideal
tachometer).  The kernels are the arithmetic both loops call (:mod:`twin.sim.loop`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit

from controllers.blocks.signals import AXIS_SIGNALS, FIRST_AXIS_INDEX, OFFSET, TICK_INDEX
from twin.errors import TwinInputError
from twin.numba_cache import configure as configure_numba_cache

configure_numba_cache()  # before the first @njit(cache=True): see twin.numba_cache

#: Physics steps per control period at most.
MAX_SUBSTEPS = 1_000_000


@dataclass
class Drive:
    """Saturation and transport delay between controller and actuator.

    The input applied at physics step ``j`` (counted from the start of the run) is the
    saturated command of tick ``(j - delay_steps) // substeps``, or zero before the first
    delayed command arrives; a delay that is not a whole number of ticks falls inside one.

    Parameters
    ----------
    n_axes : int
    substeps : int
        Physics steps per control period.
    timestep_s : float
        Physics timestep (s).
    delay_s : float
        Transport delay (s); rounded to whole physics steps (must be within 1e-9 s of one).
    saturation_V : float or None
        Symmetric limit on the applied input (V); None for none.
    """

    n_axes: int
    substeps: int
    timestep_s: float
    delay_s: float = 0.0
    saturation_V: float | None = None

    def __post_init__(self):
        steps = self.delay_s / self.timestep_s
        if (
            not (0 <= self.delay_s <= 10.0 and math.isfinite(steps))
            or abs(steps - round(steps)) * self.timestep_s > 1e-9
        ):
            raise TwinInputError(
                "drive.delay_s",
                self.delay_s,
                f"must be in [0, 10] s and a whole multiple of the timestep {self.timestep_s:g} s",
            )
        if self.saturation_V is not None and self.saturation_V <= 0:
            raise TwinInputError("drive.saturation_V", self.saturation_V, "must be > 0")
        self.delay_steps = round(steps)
        self.delay_ticks = self.delay_steps // self.substeps

    @property
    def limit_V(self) -> float:
        """Saturation limit (V); ``inf`` when there is none."""
        return math.inf if self.saturation_V is None else float(self.saturation_V)

    def delay_line(self) -> np.ndarray:
        """A fresh delay buffer: the saturated commands of the last ``delay_ticks + 2`` ticks
        (V), shape (delay_ticks + 2, n_axes), indexed by tick modulo its length."""
        return np.zeros((self.delay_ticks + 2, self.n_axes))


#: What the loops close on: position on the table's linear scale and velocity on the motor's
#: encoder (``"dual"``, a drive's usual set-up), both on the scale (``"table"``, a fully closed
#: loop) or both on the motor's encoder (``"motor"``, a semi-closed loop).  An axis without a
#: motor joint (a linear motor) reads its scale in all three.
FEEDBACK = ("dual", "table", "motor")


@dataclass
class Encoder:
    """Quantized, noisy position measurement.

    Parameters
    ----------
    resolution_m : ndarray, shape (n_axes,)
        Resolution of the table's encoder, a linear scale (m); 0 for ideal.
    noise_std_m : ndarray, shape (n_axes,)
        Standard deviation of additive Gaussian noise on the position loop's reading (m).
    gains : ndarray, shape (n_axes,)
        Sensor gain (the machine's H1).
    seed : int
        Seed of the noise generator.
    velocity : {"backward_difference", "tachometer"}
        Velocity measurement: backward difference of the encoder (the papers' drives) or an
        ideal tachometer where the encoder is.
    feedback : {"dual", "table", "motor"}
        What the loops close on (:data:`FEEDBACK`); the motor's encoder reads in table travel
        (motor angle x lead / gear ratio).
    motor_resolution_m : ndarray, shape (n_axes,), optional
        Resolution of the motor's encoder in table travel (m; 0 for ideal), wherever a loop
        reads the motor; default ideal.
    """

    resolution_m: np.ndarray
    noise_std_m: np.ndarray
    gains: np.ndarray
    seed: int = 0
    velocity: str = "backward_difference"
    feedback: str = "table"
    motor_resolution_m: np.ndarray | None = None

    def __post_init__(self):
        if self.motor_resolution_m is None:
            self.motor_resolution_m = np.zeros(len(self.gains))
        for name in ("resolution_m", "noise_std_m", "motor_resolution_m"):
            arr = np.asarray(getattr(self, name), float)
            if (arr < 0).any() or not np.isfinite(arr).all():
                raise TwinInputError(f"sensors.{name}", arr.tolist(), "must be finite and >= 0")
            setattr(self, name, arr)
        self.gains = np.asarray(self.gains, float)
        if self.velocity not in ("backward_difference", "tachometer"):
            raise TwinInputError("sensors.velocity", self.velocity, "must be 'backward_difference' or 'tachometer'")
        if self.feedback not in FEEDBACK:
            raise TwinInputError("sensors.feedback", self.feedback, f"must be one of {', '.join(FEEDBACK)}")

    def noise_source(self):
        """``draw(n_ticks)`` -> the next ``n_ticks`` rows of the run's measurement noise (m),
        shape (n_ticks, n_axes), from one generator seeded with ``seed``: drawing in chunks
        gives the same sequence as drawing at once."""
        rng = np.random.default_rng(self.seed)
        return lambda n_ticks: rng.standard_normal((n_ticks, len(self.gains))) * self.noise_std_m


def substeps_per_tick(control_period_s: float, timestep_s: float) -> int:
    """Whole number of physics steps per control period.

    Raises
    ------
    TwinInputError
        If the control period is not a whole multiple of the timestep.
    """
    if timestep_s <= 0 or not math.isfinite(timestep_s):
        raise TwinInputError("timestep_s", timestep_s, "must be > 0")
    ratio = control_period_s / timestep_s
    if not ratio <= MAX_SUBSTEPS:
        raise TwinInputError(
            "control_period_s",
            control_period_s,
            f"more than {MAX_SUBSTEPS:,} physics steps of {timestep_s:g} s per control period",
        )
    n = round(ratio)
    if n < 1 or abs(ratio - n) > 1e-6:
        raise TwinInputError(
            "control_period_s", control_period_s, f"must be a whole multiple of timestep_s = {timestep_s:g} s"
        )
    return int(n)


#: Stride of the per-axis signals on the bus (:func:`controllers.blocks.signals.standard_signals`).
STRIDE = len(AXIS_SIGNALS)
# each signal's offset in its axis's block, from the one declaration (numba freezes them)
REF, REF_VEL, REF_ACC = OFFSET["ref"], OFFSET["ref_vel"], OFFSET["ref_acc"]
POS, VEL, ERROR, U_PREV = OFFSET["pos"], OFFSET["vel"], OFFSET["error"], OFFSET["u_prev"]
#: Largest magnitude MuJoCo accepts in ``ctrl``, ``qacc`` (``mjMAXVAL``); beyond it, divergence.
MAX_VALUE = 1e10


@njit(cache=True, inline="always")
def axis_signal_index(a, offset):  # pragma: no cover - compiled
    """Bus index of axis ``a``'s signal at ``offset`` in its block (:data:`REF` ... :data:`U_PREV`)."""
    return FIRST_AXIS_INDEX + STRIDE * a + offset


@njit(cache=True, inline="always")
def preview_index(n_axes, preview_ticks, a, ticks_ahead):  # pragma: no cover - compiled
    """Bus index of ``preview.<a>.<ticks_ahead>`` (1 to ``preview_ticks``) on a bus of ``n_axes``."""
    return FIRST_AXIS_INDEX + STRIDE * n_axes + a * preview_ticks + ticks_ahead - 1


@njit(cache=True, inline="always")
def table_in_bounds(qpos, q_idx, runaway_m):  # pragma: no cover - compiled
    """Whether every table position is finite and within ``runaway_m`` (m)."""
    for a in range(q_idx.shape[0]):
        if not abs(qpos[q_idx[a]]) < runaway_m:
            return False
    return True


@njit(cache=True, inline="always")
def _reading(qpos, q_idx, gain, resolution):  # pragma: no cover - compiled
    """An encoder's reading: ``gain * qpos[q_idx]`` quantized to ``resolution`` (0: ideal)."""
    y = gain * qpos[q_idx]
    if resolution > 0:
        y = np.rint(y / resolution) * resolution
    return y


@njit(cache=True, inline="always")
def sense(
    k, row, qpos, qvel, encoder_q_idx, gains, resolution, vel_q_idx, vel_v_idx, vel_gains, vel_resolution, vel_noise,
    tachometer, period_s, meas_prev, preview, noise, ref, u_prev, bus,
):  # pragma: no cover - compiled  # fmt: skip
    """Write tick ``k``'s loop signals onto the bus (layout of ``standard_signals``).

    The arguments after ``qvel`` are the fields of a :class:`twin.sim.loop.Sensor` (the loop
    takes them out of it once, before its first tick: numba counts a reference each time an
    array is taken out of a tuple), then the chunk's ``noise`` (n, n_axes) and ``ref``
    (n + preview, n_axes, 3), in which ``row`` is tick k's row.  The position encoder reads
    ``gains * qpos[encoder_q_idx]`` quantized to ``resolution`` (m; 0 for ideal) plus noise.  The
    velocity encoder reads ``vel_gains * qpos[vel_q_idx]`` quantized to ``vel_resolution``, plus
    ``vel_noise`` times the same noise (1 where both are one encoder, whose reading is then taken
    once, 0 for a second one); the
    velocity is its ``(y[k] - y[k-1]) / period_s`` (0 at k = 0) or, with ``tachometer``,
    ``vel_gains * qvel[vel_v_idx]``.  ``meas_prev`` (the velocity encoder's last reading) is
    updated in place; ``u_prev`` is the command the controller knows it applied last tick (V).
    """
    n_axes = encoder_q_idx.shape[0]
    bus[TICK_INDEX] = k
    for a in range(n_axes):
        y = _reading(qpos, encoder_q_idx[a], gains[a], resolution[a]) + noise[row, a]
        if vel_noise[a] == 1.0:  # the position encoder itself: its reading, not read again
            y_vel = y
        else:
            y_vel = _reading(qpos, vel_q_idx[a], vel_gains[a], vel_resolution[a]) + vel_noise[a] * noise[row, a]
        base = axis_signal_index(a, 0)
        bus[base + REF] = ref[row, a, 0]
        bus[base + REF_VEL] = ref[row, a, 1]
        bus[base + REF_ACC] = ref[row, a, 2]
        bus[base + POS] = y
        if tachometer:
            bus[base + VEL] = vel_gains[a] * qvel[vel_v_idx[a]]
        else:
            bus[base + VEL] = (y_vel - meas_prev[a]) / period_s if k > 0 else 0.0
        bus[base + ERROR] = ref[row, a, 0] - y
        bus[base + U_PREV] = u_prev[a]
        meas_prev[a] = y_vel
        for i in range(preview):
            bus[preview_index(n_axes, preview, a, i + 1)] = ref[row + 1 + i, a, 0]


@njit(cache=True, inline="always")
def drive_command(k, row, bus, u_idx, u_dist, limit, u, ua, u_sat, delay_line):  # pragma: no cover - compiled
    """Tick ``k``'s controller outputs ``u`` (from the bus at ``u_idx``), drive input
    ``ua = clip(u + u_dist[row], -limit, limit)`` (V, stored in ``delay_line``) and
    ``u_sat = clip(u, -limit, limit)`` (V): what the controller knows it applied (the next
    tick's ``u_prev``; the disturbance is unknown to it); the arrays are a
    :class:`twin.sim.loop.DriveState`'s.

    Returns False if an input is not finite or beyond :data:`MAX_VALUE` (divergence).
    """
    ok = True
    n = delay_line.shape[0]
    for a in range(u_idx.shape[0]):
        u[a] = bus[u_idx[a]]
        u_sat[a] = min(max(u[a], -limit), limit)
        ua[a] = min(max(u[a] + u_dist[row, a], -limit), limit)
        delay_line[k % n, a] = ua[a]
        if not abs(ua[a]) <= MAX_VALUE:
            ok = False
    return ok


@njit(cache=True, inline="always")
def actuator_input(k, s, substeps, delay_steps, delay_line, act_idx, ctrl):  # pragma: no cover - compiled
    """Set each axis's actuator ``ctrl[act_idx[a]]`` for physics step ``s`` of tick ``k``:
    the command of tick ``(k substeps + s - delay_steps) // substeps`` from ``delay_line``, or 0
    before the first one arrives (a :class:`twin.sim.loop.DriveState`'s fields)."""
    j = k * substeps + s - delay_steps
    n = delay_line.shape[0]
    for a in range(act_idx.shape[0]):
        ctrl[act_idx[a]] = delay_line[(j // substeps) % n, a] if j >= 0 else 0.0


@njit(cache=True, inline="always")
def accelerations_ok(qacc):  # pragma: no cover - compiled
    """MuJoCo's own instability test (``mjWARN_BADQACC``): every acceleration finite and within
    :data:`MAX_VALUE`."""
    for i in range(qacc.shape[0]):
        if not abs(qacc[i]) <= MAX_VALUE:
            return False
    return True
