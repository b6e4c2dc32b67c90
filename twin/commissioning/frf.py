"""Frequency-response measurement on the twin, as a drive's commissioning tool does it.

An excitation ``d`` (PRBS, logarithmic chirp or multisine of random phases and low crest factor,
volts) is added to one
axis's drive input, with the loop open or closed around the axis (a velocity loop: derivative
feedback of the position; a position loop: PD; on the motor's encoder by default, as a drive
closes it, collocated with the drive), and the plant's FRF from drive input ``u`` (V)
to the sensor's position (m; the table's, or the motor's in table travel) is estimated from the
recorded signals with Welch's averaged cross spectra (``scipy.signal.csd``):

    G = S_dy / S_du,      coherence = |S_du|^2 / (S_dd S_uu) x |S_dy|^2 / (S_dd S_yy)

In the open loop ``u = d`` and G is the H1 estimator S_uy / S_uu; in a closed loop the ratio
through the excitation removes the feedback's correlation (the indirect method). Resonances
and anti-resonances are the local maxima and minima of the magnitude (prominence >= 3 dB, with
coherence >= 0.9); each is marked unreliable, with the reason, where the coherence within 5 % of
it falls under 0.95 (:func:`mode_quality`: Coulomb friction's distortion). The model's FRF is the
zero-order-hold equivalent of the machine's transfer function at the sample period, with the
drive delay.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, Literal

import numpy as np
from scipy import signal

from controllers.blocks import error_feedback, open_loop, sum_of
from controllers.lti import SisoTf
from twin.errors import SimulationDiverged, TwinInputError
from twin.machines import BuiltMachine, build, get_machine
from twin.machines.datasheet import DatasheetMachine
from twin.references import Step
from twin.sim.drive import Encoder
from twin.sim.runner import simulate
from twin.spec import axes_indices

if TYPE_CHECKING:
    from twin.sim.runner import RunResult

LOOPS = ("open", "velocity", "position")
SENSORS = ("motor", "table")
EXCITATIONS = ("prbs", "chirp", "multisine")
#: Sample period (s) of the measurement: the control period of a modern drive.
SAMPLE_PERIOD_S = 1e-4
#: Most seconds one measurement may simulate (memory and time stay bounded).
MAX_DURATION_S = 120.0
#: Welch segment length (samples): 1.6 s at 0.1 ms, a 0.61 Hz resolution.
SEGMENT = 16384
#: The highest frequency of a chirp, as a fraction of the sample rate (below its Nyquist 0.5).
CHIRP_TOP_PER_SAMPLE_RATE = 0.45
#: Peaks of the magnitude this prominent (dB) and this coherent count as (anti-)resonances.
PEAK_PROMINENCE_DB = 3.0
#: ... within this factor of its frequency on either side.
PEAK_SPAN = 1.5
MIN_COHERENCE = 0.9
#: Most decay of a mode per physics step (zeta omega h) in a measurement: its frequency then
#: reads about 0.1 % high (:func:`measurement_timestep`).
MAX_DECAY_PER_STEP = 1.5e-3
#: A peak's natural frequency is fitted over the lines within this factor of its frequency,
#: at least this many on either side, with this many reweighting iterations.
MODAL_SPAN = 1.15
MODAL_LINES = 6
MODAL_ITERATIONS = 5
#: ... and by this many standard deviations of the magnitude (median over this many lines on
#: either side), where the estimate gives them (a multisine's BLA).
PEAK_UNCERTAINTIES = 3.0
PEAK_LINES = 4
#: A multisine's period (samples: 0.82 s at 0.1 ms, 1.22 Hz lines), the periods each
#: realization is measured over after one period of settling, and the fewest realizations.
MULTISINE_PERIOD = 8192
MULTISINE_PERIODS = 2
MIN_REALIZATIONS = 4
#: A multisine's crest factor is lowered by this many clippings at this fraction of its peak
#: (:func:`low_crest_period`).
CREST_ITERATIONS = 200
CREST_CLIP = 0.8
#: A reported mode is unreliable where the coherence falls below MODE_MIN_COHERENCE on a line
#: within MODE_BAND of its frequency (:func:`mode_quality`).
MODE_BAND = 0.05
MODE_MIN_COHERENCE = 0.95
#: Lines of low coherence with at most this many coherent lines between count as one band.
BAND_GAP_LINES = 3
#: The smallest excitation (V): a +-10 V analogue command's 16-bit step is 0.3 mV, a field bus's
#: torque command's 0.1 % of rated torque 10 mV of a 10 V scale; below it a drive does not move
#: (1e-300 V overflowed the estimator's spectra).
MIN_AMPLITUDE_V = 1e-3


@dataclass(frozen=True)
class FrfSettings:
    """What one measurement does.

    Attributes
    ----------
    axis : str
    loop : {"open", "velocity", "position"}
    sensor : {"motor", "table"}
    excitation : {"prbs", "chirp", "multisine"}
    amplitude_V : float
        Excitation amplitude (V, peak).
    duration_s : float
        Recorded time (s), after 0.5 s of settling.
    f_max_hz : float
        Highest frequency reported (Hz), at most 0.4 / the sample period.
    seed : int
        Random seed of the PRBS and multisine.
    feedback : {"motor", "table"}
        The encoder the loop closes on: the motor's (in table travel, as a drive closes its
        velocity loop; an axis without a motor has its table's only) or the table's.
    """

    axis: str = "x"
    loop: Literal["open", "velocity", "position"] = "velocity"
    sensor: Literal["motor", "table"] = "table"
    excitation: Literal["prbs", "chirp", "multisine"] = "prbs"
    amplitude_V: float = 1.0
    duration_s: float = 16.0
    f_max_hz: float = 1000.0
    seed: int = 1
    feedback: Literal["motor", "table"] = "motor"

    def check(self) -> None:
        """Refuse a value out of range, naming its option."""
        for name, value, allowed in (
            ("--loop", self.loop, LOOPS),
            ("--sensor", self.sensor, SENSORS),
            ("--excitation", self.excitation, EXCITATIONS),
            ("--feedback", self.feedback, ("motor", "table")),
        ):
            if value not in allowed:
                raise TwinInputError(name, value, f"must be one of {', '.join(allowed)}")
        if not (0 <= self.seed < 2**32):
            raise TwinInputError("--seed", self.seed, "must be in [0, 2**32)")
        if not (MIN_AMPLITUDE_V <= self.amplitude_V <= 10):
            raise TwinInputError("--amplitude", self.amplitude_V, f"must be in [{MIN_AMPLITUDE_V:g}, 10] V")
        if not (2 * SEGMENT * SAMPLE_PERIOD_S <= self.duration_s <= MAX_DURATION_S):
            raise TwinInputError(
                "--duration", self.duration_s, f"must be in [{2 * SEGMENT * SAMPLE_PERIOD_S:g}, {MAX_DURATION_S:g}] s"
            )
        if not (10 <= self.f_max_hz <= 0.4 / SAMPLE_PERIOD_S):
            raise TwinInputError("--f-max", self.f_max_hz, f"must be in [10, {0.4 / SAMPLE_PERIOD_S:g}] Hz")
        shortest = MIN_REALIZATIONS * (1 + MULTISINE_PERIODS) * MULTISINE_PERIOD * SAMPLE_PERIOD_S
        if self.excitation == "multisine" and self.duration_s < shortest:
            raise TwinInputError(
                "--duration",
                self.duration_s,
                f"a multisine needs {MIN_REALIZATIONS} realizations of {1 + MULTISINE_PERIODS} periods: "
                f"at least {math.ceil(10 * shortest) / 10:g} s",
            )


def sample_period(bm: BuiltMachine) -> float:
    """The measurement's sample period (s): the whole number of physics steps nearest
    :data:`SAMPLE_PERIOD_S`, at least one."""
    return max(1, round(SAMPLE_PERIOD_S / bm.model.opt.timestep)) * bm.model.opt.timestep


def measurement_timestep(bm: BuiltMachine) -> float | None:
    """The physics step (s) a measurement runs at: the machine's, or a whole fraction of it
    where that keeps :data:`MAX_DECAY_PER_STEP` on the model's fastest-decaying mode; None
    where the machine's step already does.

    MuJoCo's Euler integrator treats the drive train's spring dampers (tendons) explicitly:
    a mode of damping ratio zeta at omega reads about 0.7 zeta omega h high (heavy_xy X's
    432.06 Hz mode 434.02 Hz at the files' 50 us, 432.95 at 25 us: first order in h), which
    the FRF showed as a bias of +0.3 to +0.8 %."""
    decay = max(
        (-complex(p).real for i in range(len(bm.axes)) for p in np.roots(bm.plant[i][i].den) if p.imag > 0),
        default=0.0,
    )
    step = bm.model.opt.timestep
    if decay * step <= MAX_DECAY_PER_STEP:
        return None
    return step / math.ceil(decay * step / MAX_DECAY_PER_STEP)


def excitation_signal(kind: str, n: int, dt: float, amplitude: float, f_max_hz: float, seed: int) -> np.ndarray:
    """The excitation (V), ``n`` samples at ``dt``.

    prbs: a maximum-length sequence (``scipy.signal.max_len_seq``) of +-amplitude, each bit held
    for ``round(0.4 / (f_max dt))`` samples (flat spectrum to about f_max); chirp: logarithmic
    sweep from 1 Hz (``scipy.signal.chirp``) that reaches f_max a :data:`SEGMENT` before the
    record's end (a quarter of a shorter record) and goes on to at most
    :data:`CHIRP_TOP_PER_SAMPLE_RATE` / dt; multisine: realizations
    (:func:`multisine_realizations`), each every DFT line of a :data:`MULTISINE_PERIOD`-sample
    period up to f_max with its own random phases, its crest factor lowered
    (:func:`low_crest_period`), scaled to the amplitude's peak and repeated for
    1 + :data:`MULTISINE_PERIODS` periods.
    """
    rng = np.random.default_rng(seed)
    if kind == "prbs":
        hold = max(1, round(0.4 / (f_max_hz * dt)))
        bits = math.ceil(math.log2(n / hold + 1))
        seq = signal.max_len_seq(bits, state=rng.integers(0, 2, bits) | np.r_[1, np.zeros(bits - 1, int)])[0]
        return amplitude * (2.0 * np.repeat(seq, hold)[:n] - 1.0)
    t = np.arange(n) * dt
    if kind == "chirp":
        # reach f_max a Welch segment before the end (a quarter of a short record), then sweep
        # on at the same rate: the band's top lies inside whole segments, not under the last
        # one's closing window (compact_xy Y's 784.6 Hz mode, swept at 15.4 of 16 s, read 775 Hz)
        lead = min(SEGMENT, n // 4)
        top = min(f_max_hz ** (n / (n - lead)), CHIRP_TOP_PER_SAMPLE_RATE / dt)
        return amplitude * signal.chirp(t, 1.0, t[-1], top, method="logarithmic", phi=-90)
    lines = np.arange(1, int(f_max_hz * MULTISINE_PERIOD * dt) + 1)
    blocks = []
    for _ in range(max(1, multisine_realizations(n))):
        one = low_crest_period(np.exp(2j * math.pi * rng.random(len(lines))), lines)
        blocks.append(np.tile(one / np.abs(one).max(), 1 + MULTISINE_PERIODS))
    return amplitude * np.resize(np.concatenate(blocks), n)


def low_crest_period(phasors: np.ndarray, lines: np.ndarray) -> np.ndarray:
    """One period (:data:`MULTISINE_PERIOD` samples) of the unit-amplitude multisine on the DFT
    ``lines`` with the starting ``phasors``, its crest factor (peak / RMS) lowered by
    time-frequency swapping (Van der Ouderaa, Schoukens and Renneboog, IEEE Trans. Instrum.
    Meas. 37(1), 1988): clip the period at :data:`CREST_CLIP` of its peak, keep the phases of
    the clipped period's excited lines at unit amplitude, :data:`CREST_ITERATIONS` times.

    Random phases give a crest factor of about 3.6 on 819 lines, the swapping about 1.7: at the
    same peak 2.1 times the RMS (+6.5 dB a line), as much as a PRBS of that peak puts below
    its f_max.  Coulomb friction's equivalent damping falls with the velocity's RMS: at random
    phases mid_size_xy Y's 270.97 Hz mode read 262.0 Hz (-3.3 %, the table sticking), here
    within 1 %."""
    spectrum = np.zeros(MULTISINE_PERIOD // 2 + 1, complex)
    spectrum[lines] = phasors
    for _ in range(CREST_ITERATIONS):
        period = np.fft.irfft(spectrum, MULTISINE_PERIOD)
        limit = CREST_CLIP * np.abs(period).max()
        clipped = np.fft.rfft(np.clip(period, -limit, limit))[lines]
        spectrum[lines] = np.exp(1j * np.angle(clipped))
    return np.fft.irfft(spectrum, MULTISINE_PERIOD)


def multisine_realizations(n: int) -> int:
    """How many whole realizations (1 + :data:`MULTISINE_PERIODS` periods each) a record of
    ``n`` samples holds."""
    return n // ((1 + MULTISINE_PERIODS) * MULTISINE_PERIOD)


def welch_frf(d: np.ndarray, u: np.ndarray, y: np.ndarray, dt: float, f_max_hz: float) -> dict:
    """The FRF G = S_dy / S_du and its coherence (see the module docstring) from Welch's averaged
    cross spectra of the excitation ``d``, the drive input ``u`` (V) and the position ``y`` (m),
    sampled at ``dt``, on the lines from the second to ``f_max_hz``."""
    kw = dict(fs=1.0 / dt, nperseg=SEGMENT, window="hann", detrend="linear")
    freqs, s_du = signal.csd(d, u, **kw)
    _, s_dy = signal.csd(d, y, **kw)
    _, s_dd = signal.welch(d, **kw)
    _, s_uu = signal.welch(u, **kw)
    _, s_yy = signal.welch(y, **kw)
    band = (freqs >= 2.0 / (SEGMENT * dt)) & (freqs <= f_max_hz)
    return {
        "frequency_hz": freqs[band],
        "frf": s_dy[band] / s_du[band],
        "coherence": _coherence(s_du[band], s_dy[band], s_dd[band], s_uu[band], s_yy[band]),
    }


def _coherence(s_du, s_dy, s_dd, s_uu, s_yy) -> np.ndarray:
    """The product of the excitation's coherence with the input and with the output."""
    return np.clip(np.abs(s_du) ** 2 / (s_dd * s_uu) * np.abs(s_dy) ** 2 / (s_dd * s_yy), 0.0, 1.0)


def multisine_frf(d: np.ndarray, u: np.ndarray, y: np.ndarray, dt: float, f_max_hz: float) -> dict:
    """The best linear approximation (BLA) from a multisine's realizations, with the noise and the
    nonlinear distortion on it per line (Pintelon and Schoukens, System Identification, ch. 3-4).

    Each realization's periods after the first (settling) are taken whole (no window: the
    excitation is periodic) and averaged; the position through its sample differences, so an
    open loop's drift falls on the DC line only.  Over the realizations, G = S_dy / S_du (the
    ratio through the excitation, as for Welch) and the coherence as for Welch: a nonlinearity
    such as Coulomb friction adds to each realization's output what does not repeat from one
    set of random phases to the next, so it lowers the coherence here (within one periodic
    excitation it repeats exactly and looked coherent).  The noise's variance on G comes from
    the spread over the periods, the total from the spread over the realizations, and the
    stochastic nonlinear distortion is their difference.

    Returns
    -------
    dict
        ``frequency_hz`` (the excited lines up to ``f_max_hz``), ``frf`` (m/V), ``coherence``,
        ``noise_db`` and ``distortion_db`` (the standard deviations on G, dB re 1 m/V; -inf
        where none), ``spread`` (G's standard deviation, noise and distortion together, m/V),
        ``realizations``.
    """
    realizations = multisine_realizations(len(d))
    n, p = MULTISINE_PERIOD, MULTISINE_PERIODS

    def measured_periods(x: np.ndarray) -> np.ndarray:
        """(realization, period, sample) of the periods after each realization's first."""
        return x[: realizations * (1 + p) * n].reshape(realizations, 1 + p, n)[:, 1:, :]

    lines = np.arange(1, int(f_max_hz * n * dt) + 1)
    spectra = {name: np.fft.rfft(measured_periods(x), axis=2)[:, :, lines] for name, x in (("d", d), ("u", u))}
    steps = np.diff(y, prepend=y[0])  # y[i] - y[i - 1]: a period's own samples and the one before it
    rotation = 1.0 - np.exp(-2j * math.pi * lines / n)  # a periodic signal's difference: (1 - 1/z) Y
    spectra["y"] = np.fft.rfft(measured_periods(steps), axis=2)[:, :, lines] / rotation
    ratio = spectra["y"] / spectra["u"]  # each period's G
    mean = {name: value.mean(axis=1) for name, value in spectra.items()}  # each realization's
    g_each = mean["y"] / mean["u"]

    def cross(a: str, b: str) -> np.ndarray:
        return (np.conj(mean[a]) * mean[b]).mean(axis=0)

    s_du, s_dy = cross("d", "u"), cross("d", "y")
    noise_var = ratio.var(axis=1, ddof=1).mean(axis=0) / (p * realizations)
    total_var = g_each.var(axis=0, ddof=1) / realizations
    with np.errstate(divide="ignore"):
        noise_db = 10 * np.log10(noise_var)
        distortion_db = 10 * np.log10(np.maximum(total_var - noise_var, 0.0))
    return {
        "frequency_hz": lines / (n * dt),
        "frf": s_dy / s_du,
        "coherence": _coherence(s_du, s_dy, cross("d", "d").real, cross("u", "u").real, cross("y", "y").real),
        "noise_db": noise_db,
        "distortion_db": distortion_db,
        "spread": np.sqrt(np.maximum(total_var, noise_var)),
        "realizations": realizations,
    }


def _loop_controller(bm: BuiltMachine, settings: FrfSettings, dt: float, k: int):
    """The feedback during the measurement (V per m of position error, through a 1 ms filter):
    on the measured axis, none (open loop), derivative feedback of the position for a 20 Hz
    rigid-body bandwidth (velocity loop) or a PD of 10 Hz and damping ratio 0.7 (position loop);
    the other axes always hold position with that PD."""
    parts = []
    for i, a in enumerate(bm.axes):
        loop = settings.loop if i == k else "position"
        if loop == "open":
            continue
        mass = rigid_body(bm.plant[i][i])[0]  # V s^2 / m: 1 V accelerates the axis by 1/mass
        if loop == "velocity":
            num = (mass * 2 * math.pi * 20.0, 0.0)
        else:
            w = 2 * math.pi * 10.0
            num = (2 * 0.7 * mass * w, mass * w**2)
        parts.append(error_feedback(SisoTf(num, (1e-3, 1.0)), dt, axes=(a.name,), name=f"loop.{a.name}"))
    return parts


def rigid_body(g: SisoTf) -> tuple[float, float]:
    """The rigid body of a plant ``g`` (drive input V to position m), its low-frequency
    asymptote: the drive input per acceleration (V s^2/m: 1 V accelerates it by the inverse)
    and per velocity (V s/m), the s^2 and s coefficients of the denominator over the
    numerator's constant."""
    return g.den[-3] / g.num[-1], g.den[-2] / g.num[-1]


def discretized(g: SisoTf, dt: float, method: str):
    """``g`` discretized at ``dt`` (``"zoh"``, ``"tustin"``) as a python-control state-space
    model (a tf of a compliant drive train is too badly conditioned to discretize directly)."""
    import control

    return control.c2d(control.ss(control.tf(list(g.num), list(g.den))), dt, method)


def zoh_response(g: SisoTf, dt: float, delay_s: float, freqs_hz: np.ndarray) -> np.ndarray:
    """The frequency response of ``g``'s ZOH equivalent at ``dt``, with ``delay_s`` in whole
    periods, at ``freqs_hz``: what a loop sampled at ``dt`` sees of the plant."""
    gd = discretized(g, dt, "zoh")
    z = np.exp(2j * math.pi * freqs_hz * dt)
    return np.array([complex(gd(zi)) for zi in z]) * z ** (-round(delay_s / dt))


def model_frf(bm: BuiltMachine, axis: int, sensor: str, freqs_hz: np.ndarray, dt: float) -> np.ndarray:
    """The model's FRF (m/V) at ``freqs_hz``: ZOH equivalent at ``dt`` with the drive delay."""
    return zoh_response(sensor_plant(bm, axis, sensor), dt, bm.delay_s, freqs_hz)


def sensor_plant(bm: BuiltMachine, axis: int, sensor: str) -> SisoTf:
    """The transfer function from axis ``axis``'s drive input (V) to the sensor's position (m)."""
    if sensor == "motor" and bm.motor_plant:
        return bm.motor_plant[axis]
    return bm.plant[axis][axis]


def peaks(
    freqs: np.ndarray,
    mag_db: np.ndarray,
    coherence: np.ndarray,
    uncertainty_db: np.ndarray | None = None,
    frf: np.ndarray | None = None,
) -> tuple[list[float], list[float]]:
    """Resonances and anti-resonances (Hz): coherent local maxima and minima of the magnitude
    above the rigid body's -40 dB/decade slope, prominent by PEAK_PROMINENCE_DB within a
    factor PEAK_SPAN of their frequency and, where the magnitude's standard deviation per line
    ``uncertainty_db`` is known, by PEAK_UNCERTAINTIES times its median over the peak's
    PEAK_LINES lines on either side (a BLA's scatter from friction is no mode).  Each at the
    vertex of the parabola through its line and its neighbours or, with the complex ``frf``
    (m/V), at the natural frequency of the mode fitted around it (:func:`modal_frequency`)."""
    trend = mag_db + 40.0 * np.log10(freqs)  # a rigid body is flat here
    smooth = np.convolve(np.pad(trend, 1, mode="edge"), np.ones(3) / 3, mode="valid")
    inside = (freqs > 1.02 * freqs[0]) & (freqs < 0.98 * freqs[-1])  # a peak needs both flanks
    found = []
    for sign in (1.0, -1.0):
        idx, _ = signal.find_peaks(sign * smooth, prominence=PEAK_PROMINENCE_DB)
        at = []
        for i in idx:
            if coherence[i] < MIN_COHERENCE or not inside[i] or not 3 <= i < len(freqs) - 3:
                continue
            # a mode stands out within its own neighbourhood: the prominence over
            # f / PEAK_SPAN .. f x PEAK_SPAN (a slow bend of the response, as Coulomb friction
            # leaves at low frequency, is prominent only over a decade)
            left = (freqs >= freqs[i] / PEAK_SPAN) & (freqs < freqs[i])
            right = (freqs > freqs[i]) & (freqs <= freqs[i] * PEAK_SPAN)
            if not left.any() or not right.any():
                continue
            base = max((sign * smooth[left]).min(), (sign * smooth[right]).min())
            needed = PEAK_PROMINENCE_DB
            if uncertainty_db is not None:
                near = uncertainty_db[max(0, i - PEAK_LINES) : i + PEAK_LINES + 1]
                needed = max(needed, PEAK_UNCERTAINTIES * float(np.median(near)))
            if sign * smooth[i] - base < needed:
                continue
            # the unsmoothed extreme, above the rigid body's slope as found (the raw magnitude
            # falls 2 dB a line at 5 Hz: its extreme is not the mode's)
            i = i - 1 + int(np.argmax(sign * trend[i - 1 : i + 2]))
            a, b, c = sign * trend[i - 1 : i + 2]
            # the vertex of the parabola through the line and its neighbours, where the line is
            # their extreme (then within half a line of it; else the line itself)
            shift = 0.5 * (a - c) / (a - 2 * b + c) if b >= max(a, c) and a - 2 * b + c < 0 else 0.0
            vertex = float(freqs[i] + min(max(shift, -0.5), 0.5) * (freqs[1] - freqs[0]))
            natural = None if frf is None else modal_frequency(freqs, frf, i, resonance=sign > 0)
            at.append(vertex if natural is None else natural)
        found.append(at)
    return found[0], found[1]


def modal_frequency(freqs: np.ndarray, frf: np.ndarray, i: int, resonance: bool = True) -> float | None:
    """The natural frequency (Hz) of the mode whose peak (or, ``resonance`` False, dip) of the
    complex FRF ``frf`` is on line ``i``: the modulus of the pole of a second-order rational
    fitted to ``frf`` s^2 (its reciprocal for a dip) over the lines within a factor
    :data:`MODAL_SPAN` of the line (at least :data:`MODAL_LINES` on either side), by
    Sanathanan-Koerner iterations of Levy's linear least squares.

    The peak of the magnitude is not the mode's natural frequency: with the rigid body's
    f^2 taken out, a mode of damping ratio 5.5 % peaked 1.8 % above it (heavy_xy X, the motor's
    sensor); the fitted pole is the mode's, as the model's poles (:func:`model_modes`) are.
    None where the fit finds no lightly damped pole within the span (the caller keeps the
    magnitude's vertex)."""
    f0 = freqs[i]
    span = (freqs >= f0 / MODAL_SPAN) & (freqs <= f0 * MODAL_SPAN)
    span[max(0, i - MODAL_LINES) : i + MODAL_LINES + 1] = True
    sigma = 1j * freqs[span] / f0  # s over the line's angular frequency: the fit's conditioning
    h = frf[span] * sigma**2
    if not resonance:
        h = 1.0 / h
    weight = np.ones(len(h))
    denominator = np.array([1.0, 0.0, 1.0])
    for _ in range(MODAL_ITERATIONS):
        # h (sigma^2 + a1 sigma + a0) = b2 sigma^2 + b1 sigma + b0, the unknowns a1 a0 b2 b1 b0
        columns = np.column_stack((-h * sigma, -h, sigma**2, sigma, np.ones_like(sigma))) * weight[:, None]
        rhs = h * sigma**2 * weight
        solution, *_ = np.linalg.lstsq(np.vstack((columns.real, columns.imag)), np.r_[rhs.real, rhs.imag], rcond=None)
        denominator = np.array([1.0, solution[0], solution[1]])
        weight = 1.0 / np.maximum(np.abs(np.polyval(denominator, sigma)), 1e-12)
    poles = np.roots(denominator)
    if not np.all(np.isfinite(poles)):
        return None
    pole = poles[np.argmax(poles.imag)]
    natural = float(abs(pole) * f0)
    if pole.imag <= 0 or -pole.real / abs(pole) >= 0.5 or not f0 / MODAL_SPAN <= natural <= f0 * MODAL_SPAN:
        return None
    return natural


def distortion_re_bla_db(estimate: dict, mag_db: np.ndarray) -> np.ndarray | None:
    """A multisine's stochastic nonlinear distortion on one realization's FRF, per line, in dB
    of the BLA's magnitude ``mag_db`` (``-inf`` where none is measurable); None for an estimate
    without it (Welch's)."""
    if "distortion_db" not in estimate:
        return None
    return estimate["distortion_db"] + 10 * math.log10(estimate["realizations"]) - mag_db


@dataclass(frozen=True)
class ModeQuality:
    """Whether a reported mode can be trusted (:func:`mode_quality`).

    Attributes
    ----------
    kind : {"resonance", "antiresonance"}
    frequency_hz : float
        The mode's frequency (Hz).
    coherence : float
        The lowest coherence within :data:`MODE_BAND` of it.
    distortion_db : float or None
        A multisine's highest nonlinear distortion there (dB of the BLA); None for a Welch
        estimate or where none is measurable.
    unreliable : str or None
        Why the mode is unreliable, or None.
    """

    kind: Literal["resonance", "antiresonance"]
    frequency_hz: float
    coherence: float
    distortion_db: float | None
    unreliable: str | None

    def to_json(self) -> dict[str, Any]:
        """The mode as ``twin frf --json`` prints it (one of ``modes``)."""
        return {
            "kind": self.kind,
            "frequency_hz": self.frequency_hz,
            "coherence": self.coherence,
            "distortion_db": self.distortion_db,
            "unreliable": self.unreliable,
        }


def mode_quality(
    kind: Literal["resonance", "antiresonance"],
    frequency_hz: float,
    freqs: np.ndarray,
    coherence: np.ndarray,
    distortion_db: np.ndarray | None,
) -> ModeQuality:
    """Whether a reported mode can be trusted: the lowest ``coherence`` over the lines within
    :data:`MODE_BAND` of its ``frequency_hz`` (those that decide its fit) against
    :data:`MODE_MIN_COHERENCE`, and for a multisine the highest nonlinear distortion
    ``distortion_db`` there (:func:`distortion_re_bla_db`, for information).

    Coulomb friction is not linear: at a small excitation it acts as a large equivalent damping
    (the table sticks part of the time) and the best linear approximation's modes move toward
    the stuck table's.  On the catalogue machines (multisine, 0.45 and 1 V, both sensors) every
    mode more than 0.5 % off the linear model had a line of coherence under 0.95 within 5 %
    (mid_size_xy X's 175.02 Hz mode read 170.34 Hz at 0.909, its 139.70 Hz anti-resonance
    137.98 Hz at 0.859); such a mode is marked unreliable with the reason rather than printed
    as if sound.  The nonlinear distortion tells the same (one realization's 9 and 7 dB under
    the BLA there) but not alike for peaks and dips: a dip's BLA is small, and a sound one at
    12 dB under it is common.
    """
    near = np.abs(freqs / frequency_hz - 1.0) <= MODE_BAND
    lowest = float(coherence[near].min())
    highest = None if distortion_db is None else float(distortion_db[near].max())
    reason = None
    if lowest < MODE_MIN_COHERENCE:
        reason = (
            f"coherence {lowest:.3f} < {MODE_MIN_COHERENCE:g} within {100 * MODE_BAND:g} % of it "
            "(a nonlinearity such as Coulomb friction, or noise: a larger --amplitude)"
        )
    return ModeQuality(
        kind=kind,
        frequency_hz=frequency_hz,
        coherence=lowest,
        distortion_db=highest if highest is not None and math.isfinite(highest) else None,
        unreliable=reason,
    )


def incoherent_bands(freqs: np.ndarray, coherence: np.ndarray) -> list[list[float]]:
    """The bands (Hz, [first, last line]) where the ``coherence`` is below
    :data:`MODE_MIN_COHERENCE`: runs of such lines, merged across gaps of up to
    :data:`BAND_GAP_LINES` coherent lines.  A mode within :data:`MODE_BAND` of one is
    unreliable (:func:`mode_quality`), none is read from a line under :data:`MIN_COHERENCE`
    (:func:`peaks`): a mode missing from the lists may lie inside (heavy_xy Y's 199.96 Hz
    anti-resonance, at 0.45 V of multisine, with the coherence at 0.907 beside it)."""
    low = np.flatnonzero(coherence < MODE_MIN_COHERENCE)
    if not len(low):
        return []
    breaks = np.flatnonzero(np.diff(low) > BAND_GAP_LINES + 1)
    starts, ends = low[np.r_[0, breaks + 1]], low[np.r_[breaks, len(low) - 1]]
    return [[float(freqs[a]), float(freqs[b])] for a, b in zip(starts, ends, strict=True)]


def model_modes(bm: BuiltMachine, axis: int, sensor: str) -> tuple[list[float], list[float]]:
    """The model's resonances and anti-resonances (Hz): damped natural frequencies of its poles
    and zeros with damping ratio < 0.5."""

    def frequencies(coefficients) -> list[float]:
        roots = np.roots(coefficients)
        keep = [r for r in roots if r.imag > 0 and -r.real / abs(r) < 0.5]
        return sorted(float(abs(r) / (2 * math.pi)) for r in keep)

    g = sensor_plant(bm, axis, sensor)
    return frequencies(g.den), frequencies(g.num)


def nut_stiffness(machine: str, axis: str, overrides: dict[str, float] | None = None) -> dict | None:
    """On a machine file whose stiffness follows the nut (``screw_root_diameter_m`` on ``axis``):
    the nut's position (m) and the axial (N/m) and torsional (N m/rad) stiffness there; else
    None."""
    spec = get_machine(machine)
    key = f"{axis}_nut_position_m"
    if not isinstance(spec, DatasheetMachine) or key not in spec.parameters:
        return None
    params = spec.resolve(overrides or {})
    return {
        "position_m": params[key],
        "axial_N_per_m": spec.axial_N_per_m(params, axis),
        "torsion_N_m_per_rad": spec.torsion_N_m_per_rad(params, axis),
    }


@dataclass(frozen=True)
class MultisineLevels:
    """A multisine's noise and nonlinear distortion on its BLA (:func:`multisine_frf`).

    Attributes
    ----------
    realizations : int
    noise_db, distortion_db : numpy.ndarray
        The standard deviations on the BLA per line (dB re 1 m/V; -inf where none).
    """

    realizations: int
    noise_db: np.ndarray
    distortion_db: np.ndarray


@dataclass(frozen=True)
class FrfMeasurement:
    """One axis's FRF measured on the twin (:func:`measure`).

    Attributes
    ----------
    machine : str
    settings : FrfSettings
    sample_period_s, physics_step_s : float
        The measurement's sample period and the physics step it ran at (s).
    parameters : dict
        Each parameter's value in effect (symbol: value; infinite: a rigid link).
    frequency_hz, magnitude_db, phase_deg, coherence : numpy.ndarray
        The measured lines (Hz), the magnitude (dB re 1 m/V), phase (deg) and coherence.
    model_magnitude_db, model_phase_deg : numpy.ndarray
        The model's response on the same lines.
    resonances_hz, antiresonances_hz, model_resonances_hz, model_antiresonances_hz : list of float
        The modes found (Hz), measured and the model's.
    modes : list of ModeQuality
        Each reported mode's :func:`mode_quality`.
    incoherent_bands_hz : list of list of float
        :func:`incoherent_bands`.
    collocated : bool
        Whether the sensor is collocated with the drive (else no anti-resonances are read).
    levels : MultisineLevels or None
        A multisine's noise and distortion on its BLA; None for a Welch estimate.
    coherent_share : float
        The share of the lines with coherence >= :data:`MIN_COHERENCE`.
    max_model_error_db : float or None
        The largest |measured - model| magnitude (dB) over those lines; None where there are none.
    run : twin.sim.runner.RunResult
        The simulated experiment (for plots and recordings; not JSON).
    """

    machine: str
    settings: FrfSettings
    sample_period_s: float
    physics_step_s: float
    parameters: dict[str, float]
    frequency_hz: np.ndarray
    magnitude_db: np.ndarray
    phase_deg: np.ndarray
    coherence: np.ndarray
    model_magnitude_db: np.ndarray
    model_phase_deg: np.ndarray
    resonances_hz: list[float]
    antiresonances_hz: list[float]
    model_resonances_hz: list[float]
    model_antiresonances_hz: list[float]
    modes: list[ModeQuality]
    incoherent_bands_hz: list[list[float]]
    collocated: bool
    levels: MultisineLevels | None
    coherent_share: float
    max_model_error_db: float | None
    run: RunResult

    @property
    def unreliable_modes(self) -> int:
        """How many of :attr:`modes` are marked unreliable."""
        return sum(q.unreliable is not None for q in self.modes)

    def to_json(self) -> dict[str, Any]:
        """What ``twin frf --json`` prints: ``machine``, ``settings`` (with the sample period,
        the Welch segment and the physics step), ``parameters`` (null: infinite), the lines and
        the model's, the modes found and the model's, ``modes``, ``unreliable_modes``,
        ``incoherent_bands_hz``, ``antiresonances_note``, a multisine's ``realizations``,
        ``noise_db`` and ``distortion_db``, ``coherent_share`` and ``max_model_error_db``."""
        rigid = not all(map(math.isfinite, self.parameters.values()))
        return {
            "machine": self.machine,
            "settings": {
                **self.settings.__dict__,
                "sample_period_s": self.sample_period_s,
                "segment_samples": SEGMENT,
                "physics_step_s": self.physics_step_s,
            },
            "parameters": {k: v if math.isfinite(v) else None for k, v in self.parameters.items()},
            **({"parameters_note": "null: infinite, a rigid link"} if rigid else {}),
            "frequency_hz": self.frequency_hz.tolist(),
            "magnitude_db": self.magnitude_db.tolist(),
            "phase_deg": self.phase_deg.tolist(),
            "coherence": self.coherence.tolist(),
            "model_magnitude_db": self.model_magnitude_db.tolist(),
            "model_phase_deg": self.model_phase_deg.tolist(),
            "resonances_hz": self.resonances_hz,
            "antiresonances_hz": self.antiresonances_hz,
            "model_resonances_hz": self.model_resonances_hz,
            "model_antiresonances_hz": self.model_antiresonances_hz,
            "modes": [q.to_json() for q in self.modes],
            "unreliable_modes": self.unreliable_modes,
            "incoherent_bands_hz": self.incoherent_bands_hz,
            "antiresonances_note": None
            if self.collocated
            else "the table's sensor is not collocated with the drive: "
            "its dips are not anti-resonances (measure --sensor motor)",
            **(
                {
                    "realizations": self.levels.realizations,
                    "noise_db": _finite_or_none(self.levels.noise_db),
                    "distortion_db": _finite_or_none(self.levels.distortion_db),
                    "levels_note": "standard deviations on the BLA (dB re 1 m/V); null: none measurable",
                }
                if self.levels is not None
                else {}
            ),
            "coherent_share": self.coherent_share,
            "max_model_error_db": self.max_model_error_db,
        }


@dataclass(frozen=True)
class FrfExperiment:
    """One measurement set up (:meth:`plan`), to :meth:`run` on the twin and :meth:`estimate`
    from.

    Attributes
    ----------
    machine : str
    settings : FrfSettings
    bm : twin.machines.BuiltMachine
        The machine, at the measurement's physics step (:func:`measurement_timestep`).
    axis : int
        The measured axis's index.
    sample_period_s : float
    settle : int
        Samples of settling before the record.
    excitation_V : numpy.ndarray
        (samples, axes): the excitation added to the drive inputs.
    """

    machine: str
    settings: FrfSettings
    bm: BuiltMachine
    axis: int
    sample_period_s: float
    settle: int
    excitation_V: np.ndarray

    @classmethod
    def plan(cls, machine: str, settings: FrfSettings, overrides: dict[str, float] | None = None) -> FrfExperiment:
        """The measurement of ``settings`` on ``machine`` (with ``overrides``), checked.

        Raises
        ------
        TwinInputError
            An unknown machine, axis, parameter or option value.
        """
        settings.check()
        bm = build(machine, overrides)
        finer = measurement_timestep(bm)
        if finer is not None:
            bm = build(machine, overrides, finer)
        names = [a.name for a in bm.axes]
        (k,) = axes_indices([settings.axis], names, "--axis")
        dt = sample_period(bm)
        settle = round(0.5 / dt)
        n = settle + round(settings.duration_s / dt)
        d = np.zeros((n, len(names)))
        d[settle:, k] = excitation_signal(
            settings.excitation, n - settle, dt, settings.amplitude_V, settings.f_max_hz, settings.seed
        )
        return cls(machine, settings, bm, k, dt, settle, d)

    def run(self) -> RunResult:
        """The experiment simulated: the excitation on the drive input, the loop closed as the
        settings say.

        Raises
        ------
        SimulationDiverged
            The measurement's loop is unstable on this axis (with the option to try).
        """
        bm, settings, dt = self.bm, self.settings, self.sample_period_s
        names = [a.name for a in bm.axes]
        controller = sum_of(
            [*_loop_controller(bm, settings, dt, self.axis), open_loop(self.excitation_V, dt, names, name="excitation")]
        )
        encoder = Encoder(
            np.zeros(len(names)), np.zeros(len(names)), np.array(bm.sensor_gains), feedback=settings.feedback
        )
        n = len(self.excitation_V)
        try:
            return simulate(
                bm,
                controller,
                Step(0.0, n_axes=len(names)),
                n * dt,
                dt,
                encoder=encoder,
                progress=False,
                record_every=1,
            )
        except SimulationDiverged as exc:
            advice = (
                "--loop open"
                if settings.feedback == "motor" or bm.axes[self.axis].motor_joint is None
                else "--feedback motor"
            )
            diverged = SimulationDiverged(
                exc.sim_time_s,
                f"{exc.reason} (the measurement's {settings.loop} loop on the {settings.feedback} "
                f"encoder is unstable on this axis: try {advice})",
            )
            diverged.result = exc.result
            raise diverged from None

    def estimate(self, run: RunResult) -> FrfMeasurement:
        """The FRF, its coherence and modes from the recorded ``run``, beside the model's."""
        bm, settings, dt, k, settle = self.bm, self.settings, self.sample_period_s, self.axis, self.settle
        u = run.u_applied_V[settle:, k]
        motor = bm.axes[k].motor_joint
        if settings.sensor == "motor" and motor is not None:
            y = run.qpos[settle:][:, bm.joint_qpos_index(motor)] * bm.motor_travel_m_per_rad[bm.axes[k].name]
        else:
            y = run.table_position_m()[settle:, k]
        estimate = (multisine_frf if settings.excitation == "multisine" else welch_frf)(
            self.excitation_V[settle:, k], u, y, dt, settings.f_max_hz
        )
        freqs, g, coherence = estimate["frequency_hz"], estimate["frf"], estimate["coherence"]
        model = model_frf(bm, k, settings.sensor, freqs, dt)
        mag_db, model_db = 20 * np.log10(np.abs(g)), 20 * np.log10(np.abs(model))
        uncertainty_db = None
        if "spread" in estimate:  # the BLA's standard deviation, in dB of its magnitude
            uncertainty_db = 20 * np.log10(1 + estimate["spread"] / np.abs(g))
        # the peaks' modes are fitted with the drive's delay and the hold's half sample taken out
        undelayed = g * np.exp(2j * math.pi * freqs * (bm.delay_s + dt / 2))
        resonances, antiresonances = peaks(freqs, mag_db, coherence, uncertainty_db, undelayed)
        model_res, model_anti = model_modes(bm, k, settings.sensor)
        # a dip of a sensor away from the drive (the table of a ball screw) is no anti-resonance:
        # a non-collocated transfer function has no zeros there
        collocated = settings.sensor == "motor" or bm.axes[k].motor_joint is None
        if not collocated:
            antiresonances = []
        distortion_db = distortion_re_bla_db(estimate, mag_db)
        kinds: tuple[tuple[Literal["resonance", "antiresonance"], list[float]], ...] = (
            ("resonance", resonances),
            ("antiresonance", antiresonances),
        )
        quality = [mode_quality(kind, f, freqs, coherence, distortion_db) for kind, found in kinds for f in found]
        good = coherence >= MIN_COHERENCE
        levels = None
        if "distortion_db" in estimate:
            levels = MultisineLevels(estimate["realizations"], estimate["noise_db"], estimate["distortion_db"])
        return FrfMeasurement(
            machine=self.machine,
            settings=settings,
            sample_period_s=dt,
            physics_step_s=bm.model.opt.timestep,
            parameters=dict(bm.params),
            frequency_hz=freqs,
            magnitude_db=mag_db,
            phase_deg=np.degrees(np.angle(g)),
            coherence=coherence,
            model_magnitude_db=model_db,
            model_phase_deg=np.degrees(np.angle(model)),
            resonances_hz=resonances,
            antiresonances_hz=antiresonances,
            model_resonances_hz=model_res,
            model_antiresonances_hz=model_anti,
            modes=quality,
            incoherent_bands_hz=incoherent_bands(freqs, coherence),
            collocated=collocated,
            levels=levels,
            coherent_share=float(good.mean()),
            max_model_error_db=float(np.abs(mag_db - model_db)[good].max()) if good.any() else None,
            run=run,
        )


def measure(machine: str, settings: FrfSettings, overrides: dict[str, float] | None = None) -> FrfMeasurement:
    """Measure one axis's FRF on the twin (see the module docstring): the experiment planned
    (:meth:`FrfExperiment.plan`), run and estimated.

    Raises
    ------
    TwinInputError
        An unknown machine, axis, parameter or option value.
    SimulationDiverged
        The measurement's loop is unstable on this axis.
    """
    experiment = FrfExperiment.plan(machine, settings, overrides)
    return experiment.estimate(experiment.run())


def _finite_or_none(values: np.ndarray) -> list[float | None]:
    """A JSON list: each finite value as it is, the others as null."""
    return [float(v) if math.isfinite(v) else None for v in values]


def write_bode(measured: FrfMeasurement, path: str | Path) -> None:
    """The measured Bode plot beside the model's, with the coherence, as a PNG."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    f = measured.frequency_hz
    fig, (ax_m, ax_p, ax_c) = plt.subplots(3, 1, figsize=(9, 8), sharex=True, height_ratios=(3, 2, 1))
    ax_m.semilogx(f, measured.magnitude_db, label="measured on the twin")
    ax_m.semilogx(f, measured.model_magnitude_db, "--", label="model (transfer function)")
    for fr in measured.resonances_hz:
        ax_m.axvline(fr, color="tab:red", lw=0.8, alpha=0.6)
    for fa in measured.antiresonances_hz:
        ax_m.axvline(fa, color="tab:green", lw=0.8, alpha=0.6)
    if measured.levels is not None:  # a multisine's BLA: the levels on it
        for level, label in (
            (measured.levels.noise_db, "noise"),
            (measured.levels.distortion_db, "nonlinear distortion"),
        ):
            ax_m.semilogx(f, np.where(np.isfinite(level), level, np.nan), ".", ms=2, label=f"{label} (std on the BLA)")
    ax_m.set_ylabel("magnitude (dB re 1 m/V)")
    ax_m.legend()
    ax_p.semilogx(f, np.degrees(np.unwrap(np.radians(measured.phase_deg))))
    ax_p.semilogx(f, np.degrees(np.unwrap(np.radians(measured.model_phase_deg))), "--")
    ax_p.set_ylabel("phase (deg)")
    ax_c.semilogx(f, measured.coherence, color="k")
    ax_c.set_ylim(0, 1.05)
    ax_c.set_ylabel("coherence")
    ax_c.set_xlabel("frequency (Hz)")
    s = measured.settings
    fig.suptitle(
        f"{Path(measured.machine).name}: axis {s.axis}, {s.loop} loop on the {s.feedback} encoder, "
        f"{s.sensor} sensor, {s.excitation}"
        f" (red: resonances, green: anti-resonances)",
        fontsize=10,
    )
    for ax in (ax_m, ax_p, ax_c):
        ax.grid(True, which="both", alpha=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
