"""Controllers built from the block kinds: error feedback, cascade, Lur'e, observers, sums.

Each function returns a :class:`~controllers.blocks.core.Controller` whose blocks read the
loop's signals (:mod:`controllers.blocks.signals`) and write ``u.<axis>`` (V).  Signals a
controller uses only inside itself are named ``<controller name>:<signal>`` so that several
controllers share one bus.  Continuous models (:class:`~controllers.lti.SisoTf`, state-space
tuples or python-control models) are discretized at the control period by
:func:`controllers.lti.discretize` (Tustin by default, or zero-order hold).
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from controllers.blocks.core import Controller, Linear, Sequence, Static, Sum
from controllers.design.dob import q_response
from controllers.lti import SisoTf, delay_ticks, discretize, series, state_space, summed_inputs, tf_to_ss


def lti_block(sys, dt: float, *, inputs, outputs, method: str = "tustin", name: str = "linear") -> Linear:
    """A :class:`Linear` block from an LTI model.

    Parameters
    ----------
    sys : SisoTf, tuple (A, B, C, D) or python-control LTI
        Continuous (discretized here with ``method``), or a discrete python-control model with
        ``sys.dt == dt``; ``len(inputs)`` inputs and ``len(outputs)`` outputs, proper.
    dt : float
        Control period (s).
    method : {"tustin", "zoh"}

    Raises
    ------
    ValueError
        Wrong method, mismatched sizes or period, or an improper model.
    """
    if method not in ("tustin", "zoh"):
        raise ValueError(f"method = {method!r}: use 'tustin' or 'zoh'")
    A, B, C, D, sys_dt = state_space(sys)
    if (B.shape[1], C.shape[0]) != (len(inputs), len(outputs)):
        raise ValueError(
            f"block {name!r}: the model has {B.shape[1]} inputs and {C.shape[0]} outputs, "
            f"wired to {len(inputs)} and {len(outputs)} signals"
        )
    if sys_dt is None:
        A, B, C, D = discretize(A, B, C, D, dt=dt, method=method)
    elif not np.isclose(sys_dt, dt):
        raise ValueError(f"block {name!r}: discrete model dt = {sys_dt} differs from the control period {dt}")
    return Linear(A, B, C, D, tuple(inputs), tuple(outputs), name=name)


def error_feedback(sys, dt: float, *, axes=("x",), method: str = "tustin", name: str = "C") -> Controller:
    """``u = C(z) e`` with ``e = ref - pos`` per axis: C square, one input and output per axis."""
    axes = tuple(axes)
    block = lti_block(
        sys, dt, inputs=[f"error.{a}" for a in axes], outputs=[f"u.{a}" for a in axes], method=method, name=name
    )
    return Controller([block], dt, name)


def with_feedforward(ctrl: Controller, velocity_ff, acceleration_ff) -> Controller:
    """Add ``kv * ref_vel + ka * ref_acc`` (gains V/(m/s), V/(m/s^2), per driven axis) to u.

    Nothing is added where both gains are zero.
    """
    axes = ctrl.drives
    kv = np.broadcast_to(np.asarray(velocity_ff, float), (len(axes),))
    ka = np.broadcast_to(np.asarray(acceleration_ff, float), (len(axes),))
    if not (kv.any() or ka.any()):
        return ctrl
    inner = rename(ctrl, {f"u.{a}": f"{ctrl.name}:u.{a}" for a in axes})
    sums = [
        Sum(
            (1.0, kv[i], ka[i]),
            (f"{ctrl.name}:u.{a}", f"ref_vel.{a}", f"ref_acc.{a}"),
            f"u.{a}",
            name=f"feedforward.{a}",
        )
        for i, a in enumerate(axes)
    ]
    return Controller(inner.blocks + sums, ctrl.dt, ctrl.name)


def cascade(
    outer,
    inner,
    dt: float,
    *,
    axis: str = "x",
    velocity_ref_ff: float = 0.0,
    method: str = "tustin",
    name: str = "cascade",
    position_ref_ff: float = 0.0,
) -> Controller:
    """Position loop around a velocity loop on one axis.

    ``v_ref = C_pos(z) error + velocity_ref_ff * ref_vel + position_ref_ff * ref`` (m/s), then
    ``u = C_vel(z) (v_ref - vel)`` (V).

    Parameters
    ----------
    outer : SisoTf or python-control LTI
        Position controller, (m/s) per m, for example ``kp`` (1/s) or ``kp + ki/s``.
    inner : SisoTf or python-control LTI
        Velocity controller, V per (m/s).
    velocity_ref_ff : float
        Share of the reference velocity fed forward into the velocity reference (0..1 usually).
    position_ref_ff : float
        Gain (1/s) from the reference position into the velocity reference; with a P velocity
        loop ``kv`` it adds ``kv position_ref_ff ref`` to u (the feedforward that turns a PI-P
        cascade into its integral state feedback, Sabau 2022).
    """
    v_ref, v_err = f"{name}:v_ref.{axis}", f"{name}:v_error.{axis}"
    weights: tuple[float, ...] = (1.0, velocity_ref_ff, -1.0)
    signals: tuple[str, ...] = (v_ref, f"ref_vel.{axis}", f"vel.{axis}")
    if position_ref_ff:
        weights, signals = (*weights, position_ref_ff), (*signals, f"ref.{axis}")
    blocks = [
        lti_block(outer, dt, inputs=[f"error.{axis}"], outputs=[v_ref], method=method, name="position"),
        Sum(weights, signals, v_err, "velocity_error"),
        lti_block(inner, dt, inputs=[v_err], outputs=[f"u.{axis}"], method=method, name="velocity"),
    ]
    return Controller(blocks, dt, name)


def lure(
    sys, nonlinearity: str, *, settings, dt: float, axis: str = "x", method: str = "tustin", name: str = "lure"
) -> Controller:
    """Lur'e form: a static nonlinearity on the error, then a linear part:
    ``u = C(z) f(error)`` (see :data:`controllers.blocks.core.NONLINEARITIES`)."""
    shaped = f"{name}:f_error.{axis}"
    blocks = [
        Static(nonlinearity, tuple(settings), (f"error.{axis}",), (shaped,), "nonlinearity"),
        lti_block(sys, dt, inputs=[shaped], outputs=[f"u.{axis}"], method=method, name="linear"),
    ]
    return Controller(blocks, dt, name)


def relay_feedback(
    amplitude_V: float, hysteresis_m: float, *, dt: float, axis: str = "x", name: str = "relay"
) -> Controller:
    """Relay with hysteresis on the error, for the relay (Astrom-Hagglund) tuning experiment.

    ``u = d`` while ``error + (eps/d) u_prev >= 0``, else ``-d``: the output switches to ``+d``
    when the error rises above ``eps`` and to ``-d`` when it falls below ``-eps`` (the previous
    command fed back through the bus makes the memory; the first tick, with ``u_prev = 0`` and
    zero error, starts at ``+d``).

    Parameters
    ----------
    amplitude_V : float
        Relay amplitude d (V), > 0.
    hysteresis_m : float
        Half-width eps of the hysteresis band (m), >= 0.
    """
    for key, value, least in (("amplitude_V", amplitude_V, "> 0"), ("hysteresis_m", hysteresis_m, ">= 0")):
        number = isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)
        if not number or not (value > 0 if least == "> 0" else value >= 0):
            raise ValueError(f"{key} = {value!r}: must be a finite number {least}")
    switching = f"{name}:switching.{axis}"
    blocks = [
        Sum((1.0, hysteresis_m / amplitude_V), (f"error.{axis}", f"u_prev.{axis}"), switching, "hysteresis"),
        Static("relay", (amplitude_V,), (switching,), (f"u.{axis}",), "relay"),
    ]
    return Controller(blocks, dt, name)


#: Most control periods an observer delays ``u_prev`` by (a shift register of that many states).
MAX_OBSERVER_DELAY_TICKS = 100
#: Most first-order factors in an observer's filter Q.
MAX_OBSERVER_ORDER = 10
#: Most sinusoids a harmonic observer models.
MAX_HARMONICS = 10


def inverse_model_observer(
    plant,
    *,
    cutoff_hz: float,
    order: int,
    dt: float,
    axis: str = "x",
    method: str = "tustin",
    name: str = "dob",
    delay_s: float = 0.0,
) -> Linear:
    """Inverse-model disturbance observer: ``d_hat = Q P_n^-1 pos - Q z^-m u_prev`` (V).

    ``Q(s) = 1/(tau s + 1)^order`` with ``tau = 1/(2 pi cutoff_hz)``; ``order`` must be at least
    the relative degree of the nominal plant ``P_n`` (m/V, without its delay) so that ``Q/P_n``
    is proper.  The plant's transport delay ``delay_s`` is matched on the input side: ``u_prev``
    (the command of the previous tick, already one period old) is delayed by
    ``m = round(delay_s/dt) - 1`` more ticks, so that the position and the input the observer
    compares belong together.  Both parts are discretized with ``method``.

    Parameters
    ----------
    plant : SisoTf
        Nominal plant ``P_n`` (m/V).

    Raises
    ------
    ValueError
        A cutoff outside [1e-6 Hz, the Nyquist frequency 1/(2 dt)), ``order`` not a whole number
        from the plant's relative degree to :data:`MAX_OBSERVER_ORDER`, or a delay that is
        negative or longer than :data:`MAX_OBSERVER_DELAY_TICKS` control periods.
    """
    nyquist_hz = 0.5 / dt
    if not 1e-6 <= cutoff_hz < nyquist_hz:
        raise ValueError(
            f"cutoff_hz = {cutoff_hz!r}: must be at least 1e-6 Hz and below the Nyquist frequency {nyquist_hz:g} Hz"
        )
    if not (plant.relative_degree <= order <= MAX_OBSERVER_ORDER and int(order) == order):
        raise ValueError(
            f"order = {order!r}: must be a whole number from the plant's relative degree "
            f"{plant.relative_degree} (else Q/P_n is improper) to {MAX_OBSERVER_ORDER}"
        )
    tau = 1.0 / (2.0 * math.pi * cutoff_hz)
    q_den = np.array([1.0])
    for _ in range(int(order)):
        q_den = np.polymul(q_den, [tau, 1.0])
    if not 0 <= delay_s <= MAX_OBSERVER_DELAY_TICKS * dt:
        raise ValueError(
            f"delay_s = {delay_s!r}: must be from 0 to {MAX_OBSERVER_DELAY_TICKS} control periods "
            f"({MAX_OBSERVER_DELAY_TICKS * dt:g} s)"
        )
    lag = max(round(delay_s / dt) - 1, 0)
    from_pos = discretize(*tf_to_ss(SisoTf(plant.den, np.polymul(plant.num, q_den))), dt=dt, method=method)
    from_u = series(delay_ticks(lag), discretize(*tf_to_ss(SisoTf((-1.0,), q_den)), dt=dt, method=method))
    A, B, C, D = summed_inputs(from_pos, from_u)
    return Linear(A, B, C, D, (f"pos.{axis}", f"u_prev.{axis}"), (f"{name}:d_hat.{axis}",), name=name)


def with_correction(ctrl: Controller, observers) -> Controller:
    """Observer add-on: ``u = u_ctrl - (sum of the estimates)`` on each axis observers estimate.

    ``observers`` are blocks; those writing ``<name>:d_hat.<axis>`` (V), such as
    :func:`inverse_model_observer` or :func:`harmonic_observer`, are estimates, the others
    (delays, sums between observers) internal signals.  They run after the controller.
    """
    estimates: dict[str, list[str]] = {}
    for obs in observers:
        for out in getattr(obs, "outputs", None) or (obs.output,):
            if ":d_hat." in out:
                estimates.setdefault(out.rsplit(".", 1)[1], []).append(out)
    renames = {f"u.{a}": f"{ctrl.name}:u_ctrl.{a}" for a in estimates}
    sums = [
        Sum((1.0,) + (-1.0,) * len(outs), (renames[f"u.{a}"], *outs), f"u.{a}", f"correction.{a}")
        for a, outs in estimates.items()
    ]
    inner = rename(ctrl, renames)
    return Controller(inner.blocks + list(observers) + sums, ctrl.dt, ctrl.name)


def harmonic_estimator(frequencies_hz, bandwidth_hz: float, targets) -> SisoTf:
    """H(s) = N(s)/(s + w_o)^(2h), w_o = 2 pi bandwidth_hz, with ``H(j w_i) = targets[i]`` at each
    of the h frequencies: the internal model of the sinusoids (for targets of 1,
    ``H = 1 - prod(s^2 + w_i^2)/D``: the estimate follows each harmonic without error).
    N (degree 2h - 1, real) solves the 2h real interpolation conditions."""
    w = 2 * math.pi * np.asarray(frequencies_hz, float)
    h = len(w)
    den = np.poly(np.full(2 * h, -2 * math.pi * bandwidth_hz))
    powers = (1j * w[:, None]) ** np.arange(2 * h - 1, -1, -1)  # rows: (jw)^(2h-1) .. 1
    rhs = np.asarray(targets, complex) * np.polyval(den, 1j * w)
    num = np.linalg.solve(np.vstack([powers.real, powers.imag]), np.concatenate([rhs.real, rhs.imag]))
    return SisoTf(num, den)


def harmonic_observer(
    plant,
    *,
    frequencies_hz,
    bandwidth_hz: float,
    dt: float,
    axis: str = "x",
    method: str = "tustin",
    name: str = "dfo",
    delay_s: float = 0.0,
    cutoff_hz: float = 100.0,
    order: int = 2,
    u_signal: str | None = None,
) -> Linear:
    """Harmonic disturbance force observer: the sinusoids of known frequencies in the input
    disturbance, estimated from the inverse-model signal and predicted to when the
    correction acts.

    The inverse-model part (:func:`inverse_model_observer` with ``cutoff_hz``, ``order``)
    gives ``r = Q e^(-sT) d`` for a disturbance d at the drive input (or at the plant, a
    force); the harmonic estimator :func:`harmonic_estimator` then takes
    ``H(j w_i) = e^(j w_i T) / Q(j w_i)`` at each frequency, so the estimate equals the
    disturbance's harmonics when the correction reaches the plant, with the observer's
    dynamics set by ``bandwidth_hz`` (below the raw cutoff).  ``u_signal`` replaces
    ``u_prev.<axis>`` as the input the model compares with (to estimate what another
    observer left).

    Raises
    ------
    ValueError
        No frequency, more than :data:`MAX_HARMONICS`, two alike, one not positive or at/above
        the bandwidth, or the raw part's limits (:func:`inverse_model_observer`).
    """
    freqs = np.asarray(frequencies_hz, float).ravel()
    listing = [float(f) for f in freqs]
    if not (
        1 <= len(freqs) <= MAX_HARMONICS
        and len(set(listing)) == len(listing)
        and (freqs > 0).all()
        and (freqs < bandwidth_hz).all()
        and bandwidth_hz < cutoff_hz
    ):
        raise ValueError(
            f"frequencies_hz = {listing[:MAX_HARMONICS]}{' ...' if len(listing) > MAX_HARMONICS else ''}: "
            f"1 to {MAX_HARMONICS} different frequencies, each > 0 and below bandwidth_hz = "
            f"{bandwidth_hz!r}, which must be below cutoff_hz = {cutoff_hz!r}"
        )
    raw = inverse_model_observer(
        plant, cutoff_hz=cutoff_hz, order=order, dt=dt, axis=axis, method=method, name=f"{name}:raw", delay_s=delay_s
    )
    if u_signal is not None:
        raw = replace(raw, inputs=(f"pos.{axis}", u_signal))
    lead = round(delay_s / dt) * dt
    w = 2 * math.pi * freqs
    estimator = harmonic_estimator(freqs, bandwidth_hz, np.exp(1j * w * lead) / q_response(cutoff_hz, int(order), w))
    A, B, C, D = series((raw.A, raw.B, raw.C, raw.D), discretize(*tf_to_ss(estimator), dt=dt, method=method))
    return Linear(A, B, C, D, raw.inputs, (f"{name}:d_hat.{axis}",), name=name)


def sum_of(parts, name: str = "sum") -> Controller:
    """``u = sum of the parts' u`` on every axis they drive (same period)."""
    dts = {p.dt for p in parts}
    if len(dts) != 1:
        raise ValueError(f"controller {name!r}: parts run at different periods {sorted(dts)}")
    blocks: list = []
    terms: dict[str, list[str]] = {}
    for i, p in enumerate(parts):
        mapping = {f"u.{a}": f"{name}:part{i}.{a}" for a in p.drives}
        blocks += rename(p, mapping).blocks
        for a in p.drives:
            terms.setdefault(a, []).append(mapping[f"u.{a}"])
    sums = [Sum((1.0,) * len(t), tuple(t), f"u.{a}", f"sum.{a}") for a, t in terms.items()]
    return Controller(blocks + sums, dts.pop(), name)


def open_loop(values, dt: float, axes=("x",), name: str = "open_loop") -> Controller:
    """Plays ``values[k]`` (V), shape (n_ticks, len(axes)), ignoring the measurement."""
    return Controller([Sequence(values, tuple(f"u.{a}" for a in axes), name)], dt, name)


def rename(ctrl: Controller, mapping: dict[str, str]) -> Controller:
    """The same controller with signals renamed (``mapping`` old -> new) in every block."""

    def names(seq):
        return tuple(mapping.get(s, s) for s in seq)

    blocks: list = []
    for b in ctrl.blocks:
        if isinstance(b, Sum):
            blocks.append(replace(b, inputs=names(b.inputs), output=mapping.get(b.output, b.output)))
        elif isinstance(b, Sequence):
            blocks.append(replace(b, outputs=names(b.outputs)))
        elif isinstance(b, (Linear, Static)):
            blocks.append(replace(b, inputs=names(b.inputs), outputs=names(b.outputs)))
        else:
            raise ValueError(f"block {b.name!r} of controller {ctrl.name!r} is a Python block: it cannot be rewired")
    return Controller(blocks, ctrl.dt, ctrl.name)
