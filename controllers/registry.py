"""Controllers by name, as scenario files and the CLI refer to them.

Each entry builds a :class:`~controllers.blocks.core.Controller` of any block kind for the axes
it serves.  Gains are SI (V per m of error, ...); the description of each says its units.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from controllers.blocks import (
    NONLINEARITIES,
    Controller,
    Linear,
    Sum,
    cascade,
    error_feedback,
    harmonic_observer,
    inverse_model_observer,
    lti_block,
    lure,
    relay_feedback,
    sum_of,
    with_feedforward,
)
from controllers.design.pid import pid_tf
from controllers.lti import SisoTf
from controllers.papers import seed000, seed001, seed002, seed003


@dataclass
class Context:
    """What a builder knows besides its parameters.

    Attributes
    ----------
    dt : float
        Control period (s).
    axes : tuple of str
        The axes the controller serves (one entry of ``[controllers.<axis>]``, or every axis
        for ``[controller]``).
    method : {"tustin", "zoh"}
        Discretization of continuous models.
    plants : dict of str to SisoTf
        The machine's nominal model per axis (m/V), for model-based blocks (observers).
    parts : list of Controller
        The already built parts of a ``sum``.
    delay_s : float
        The machine's drive delay (s), for model-based blocks.
    """

    dt: float
    axes: tuple[str, ...] = ("x",)
    method: str = "tustin"
    plants: dict = field(default_factory=dict)
    parts: list = field(default_factory=list)
    delay_s: float = 0.0


def _each_axis(build_one):
    """Builder that makes one controller per served axis, ``build_one(params, ctx, axis)``."""

    def build(p, ctx):
        parts = [build_one(p, ctx, a) for a in ctx.axes]
        return Controller([b for c in parts for b in c.blocks], ctx.dt, parts[0].name)

    return build


def _per_axis_lti(make_tf):
    """Builder of an error-feedback LTI controller ``make_tf(params)`` on each served axis."""
    return _each_axis(lambda p, ctx, a: error_feedback(make_tf(p), ctx.dt, (a,), ctx.method, name=f"C.{a}"))


def _cascade(p, ctx, a):
    outer = pid_tf(p.get("kp_pos", 0.0), p.get("ki_pos", 0.0))
    inner = pid_tf(p.get("kp_vel", 0.0), p.get("ki_vel", 0.0))
    return cascade(outer, inner, ctx.dt, a, p.get("velocity_ref_ff", 0.0), ctx.method, f"cascade.{a}")


def _seed003_cascade(p, ctx, a):
    """Seed 003's cascade, designed here for the thesis's margins on the machine's model."""
    if a not in ctx.plants:
        raise ValueError(f"no model of axis {a!r} to design the cascade on")
    ff = p.get("velocity_ref_ff", 0.0)
    if not (isinstance(ff, (int, float)) and not isinstance(ff, bool) and 0.0 <= ff <= 2.0):
        raise ValueError(f"velocity_ref_ff = {ff!r}: must be a number from 0 to 2")
    gains = seed003.design_cascade(ctx.plants[a], ctx.delay_s, ctx.dt)
    return cascade(
        pid_tf(gains["kp_pos"]),
        pid_tf(gains["kp_vel"], gains["ki_vel"]),
        ctx.dt,
        a,
        float(ff),
        ctx.method,
        f"cascade.{a}",
    )


def _generic_lure(p, ctx, a):
    name = p.get("nonlinearity")
    if name not in NONLINEARITIES:
        raise ValueError(f"nonlinearity = {name!r}: use one of {', '.join(NONLINEARITIES)}")
    keys = NONLINEARITIES[name][1]
    missing = [k for k in keys if k not in p]
    if missing:
        raise ValueError(f"parameter {missing[0]!r} is needed by the {name} nonlinearity")
    settings = [p[k] for k in keys]
    return lure(SisoTf(p["num"], p["den"]), name, settings, ctx.dt, a, ctx.method, f"lure.{a}")


def _npid(p, ctx, a):
    """Seed 002 eq. (6) PID behind Ke(e) = cosh(KO e), e clipped at e_max (eqs. 7-8)."""
    settings = (p.get("ko_per_mm", seed002.KO_PER_MM) * 1e3, p.get("e_max_mm", seed002.E_MAX_MM) * 1e-3)
    return lure(seed002.pid(p.get("tf_s", 1e-4)), "cosh_gain", settings, ctx.dt, a, ctx.method, f"npid.{a}")


def _seed004(kind):
    """Seed 004's MIMO loop-shaping controller or its PID pair on axes x and y, with ZPETC
    feedforward on the reference preview (``zpetc``, default true); designed in
    :mod:`controllers.papers.seed004` (python-control, cached)."""

    def build(p, ctx):
        import control

        from controllers.papers import seed004

        if ctx.axes != ("x", "y"):
            raise ValueError(
                f"axes = {list(ctx.axes)}: seed 004's controllers serve axes x and y together "
                "([controller], not [controllers.<axis>])"
            )
        if not math.isclose(ctx.dt, seed004.DT_S):
            raise ValueError(
                f"control_period_s = {ctx.dt:g}: seed 004's controllers are designed for {seed004.DT_S:g} s"
            )
        zpetc_on, order = p.get("zpetc", True), p.get("order", "reduced")
        tuning, ki_scale = p.get("tuning", "loop_at_input"), p.get("ki_scale", 1.0)
        if not isinstance(zpetc_on, bool):
            raise ValueError(f"zpetc = {zpetc_on!r}: must be true or false")
        if (kind == "pid" and order != "reduced") or order not in ("reduced", "full"):
            raise ValueError(f"order = {order!r}: use 'reduced'" + (" or 'full'" if kind == "mimo" else ""))
        if kind == "mimo" and ("tuning" in p or "ki_scale" in p):
            raise ValueError("tuning and ki_scale are parameters of seed004_pid, not of the MIMO controller")
        seed004.check_pid_tuning(tuning, ki_scale)
        ki_scale = float(ki_scale)
        errors = [f"error.{a}" for a in ctx.axes]
        blocks = []
        if zpetc_on:
            errors = [f"zpetc:error.{a}" for a in ctx.axes]
            for a, (filt, _) in zip(ctx.axes, seed004.zpetc_filters(kind, order, tuning, ki_scale)):
                taps = max(len(filt.num), len(filt.den))
                num, den = (np.pad(c, (0, taps - len(c))) for c in (filt.num, filt.den))
                blocks += [
                    lti_block(
                        control.tf(num, den, ctx.dt),
                        ctx.dt,
                        [f"preview.{a}.{filt.preview}"],
                        [f"zpetc:ref.{a}"],
                        name=f"zpetc.{a}",
                    ),
                    Sum((1.0, -1.0), (f"zpetc:ref.{a}", f"pos.{a}"), f"zpetc:error.{a}", name=f"zpetc_error.{a}"),
                ]
        blocks.append(
            lti_block(
                seed004.controller_si(kind, order, tuning, ki_scale),
                ctx.dt,
                errors,
                [f"u.{a}" for a in ctx.axes],
                ctx.method,
                name=f"seed004_{kind}",
            )
        )
        return Controller(blocks, ctx.dt, f"seed004_{kind}")

    return build


def _seed001(p, ctx):
    """Seed 001's designs (controllers/papers/seed001.py) on each served axis, mm units in the
    design, SI on the bus."""
    design = p.get("design", "pi_p_pole_placement")
    if not isinstance(design, str) or design not in seed001.DESIGNS:
        raise ValueError(f"design = {design!r}: use one of {', '.join(seed001.DESIGNS)}")
    feedforward, velocity_ff = p.get("feedforward", True), p.get("velocity_ff", False)
    for key, v in (("feedforward", feedforward), ("velocity_ff", velocity_ff)):
        if not isinstance(v, bool):
            raise ValueError(f"{key} = {v!r}: must be true or false")
    ku, pu = p.get("ku_V_per_mm"), p.get("pu_s")
    for key, v in (("ku_V_per_mm", ku), ("pu_s", pu)):
        if v is not None and not (
            isinstance(v, (int, float)) and not isinstance(v, bool) and v > 0 and math.isfinite(v)
        ):
            raise ValueError(f"{key} = {v!r}: must be a number > 0")
    if (ku is None) != (pu is None):
        raise ValueError("ku_V_per_mm and pu_s go together")
    if not math.isclose(ctx.dt, seed001.DT_S):
        raise ValueError(f"control_period_s = {ctx.dt:g}: seed 001's designs are made for {seed001.DT_S:g} s")
    mm = seed001.MM_PER_M
    if design == "state_feedback_mimo":
        if ctx.axes != ("x", "y"):
            raise ValueError(
                f"axes = {list(ctx.axes)}: the MIMO state feedback serves axes x and y together "
                "([controller], not [controllers.<axis>])"
            )
        K, N = seed001.mimo_pole_placement()
        D = mm * np.hstack([N, -K[:, [1, 3]], -K[:, [0, 2]]])
        inputs = ("ref.x", "ref.y", "pos.x", "pos.y", "vel.x", "vel.y")
        return Controller(
            [
                Linear(
                    np.zeros((0, 0)),
                    np.zeros((0, 6)),
                    np.zeros((2, 0)),
                    D,
                    inputs,
                    ("u.x", "u.y"),
                    name="state_feedback_mimo",
                )
            ],
            ctx.dt,
            "seed001",
        )
    parts = []
    for a in ctx.axes:
        if a not in seed001.AXES:
            raise ValueError(f"axis {a!r}: seed 001 models axes x and y")
        g = seed001.design_gains(a, design, ku, pu)
        if g["form"] == "pid":
            parts.append(
                error_feedback(
                    pid_tf(mm * g["kp"], mm * g["ki"], mm * g["kd"], g["tf_s"]),
                    ctx.dt,
                    (a,),
                    ctx.method,
                    name=f"seed001.{a}",
                )
            )
        elif g["form"] == "fo_pi":
            A, B, C, D = seed001.fractional_pi_state_space(a)
            parts.append(error_feedback((A, B, mm * C, mm * D), ctx.dt, (a,), ctx.method, name=f"seed001.{a}"))
        else:
            ff = g["position_ref_ff"] if feedforward else 0.0
            parts.append(
                cascade(
                    pid_tf(g["kp"], g["ki"], g["kd"], g["tf_s"]),
                    pid_tf(mm * g["kv"]),
                    ctx.dt,
                    a,
                    0.0,
                    ctx.method,
                    f"seed001.{a}",
                    position_ref_ff=ff,
                )
            )
    ctrl = Controller([b for c in parts for b in c.blocks], ctx.dt, "seed001")
    if velocity_ff:  # the drive's VFF_GAIN: u += ref_vel / K_M, K_M = K/a (V per mm/s -> V per m/s)
        ctrl = with_feedforward(ctrl, [mm * seed001.MODEL[a][1] / seed001.MODEL[a][0] for a in ctx.axes], 0.0)
    return ctrl


def _sum(p, ctx):
    if not ctx.parts:
        raise ValueError("a sum needs at least one part")
    return sum_of(ctx.parts, "sum")


def _qualify(names, axis):
    return [n if "." in n else f"{n}.{axis}" for n in names]


def _linear(p, ctx):
    """Any state space on named signals; names without an axis are per served axis."""
    inputs, outputs = list(p.get("inputs", ["error"])), list(p.get("outputs", ["u"]))
    if p.get("domain", "discrete") not in ("discrete", "continuous"):
        raise ValueError(f"domain = {p.get('domain')!r}: use 'discrete' or 'continuous'")
    mats = [np.atleast_2d(np.asarray(p.get(k, np.zeros((0, 0))), float)) for k in "ABCD"]
    per_axis = not all("." in n for n in inputs + outputs)
    axes = ctx.axes if per_axis else (None,)
    blocks = []
    for a in axes:
        ins, outs = (_qualify(inputs, a), _qualify(outputs, a)) if a else (inputs, outputs)
        block = Linear(*mats, tuple(ins), tuple(outs), name=f"linear.{a}" if a else "linear")  # checks shapes
        if p.get("domain", "discrete") == "continuous":
            block = lti_block((block.A, block.B, block.C, block.D), ctx.dt, ins, outs, ctx.method, block.name)
        blocks.append(block)
    return Controller(blocks, ctx.dt, "linear")


#: name -> (description with units, builder(params, Context) -> Controller, parameter names)
CONTROLLERS = {
    "seed000_robust_pi": (
        "robust PI 38.33 + 45.65/s (V/m), seed 000 eqs. (18)-(19)",
        _per_axis_lti(lambda p: seed000.ROBUST_PI),
        (),
    ),
    "seed000_imc": ("IMC (0.21 s + 2)/(s + 2), seed 000 eq. (23)", _per_axis_lti(lambda p: seed000.IMC), ()),
    "seed000_hinf": ("full 4th-order H-infinity, seed 000 eq. (28)", _per_axis_lti(lambda p: seed000.HINF), ()),
    "seed000_hinf_reduced": (
        "reduced H-infinity 20.97/(s + 5.5), seed 000 eq. (29)",
        _per_axis_lti(lambda p: seed000.HINF_REDUCED),
        (),
    ),
    "seed002_pid": (
        "PID 0.8998 + 0.005155 s + 0.0006077/s (V/mm), seed 002 eq. (6); derivative filter tf_s (default 1e-4 s)",
        _per_axis_lti(lambda p: seed002.pid(p.get("tf_s", 1e-4))),
        ("tf_s",),
    ),
    "seed002_npid": (
        "nonlinear PID, seed 002 eqs. (6)-(8): eq. (6) PID behind Ke = cosh(KO e), e clipped "
        "at e_max; ko_per_mm (default 6), e_max_mm (default 0.3), tf_s (default 1e-4 s)",
        _each_axis(_npid),
        ("tf_s", "ko_per_mm", "e_max_mm"),
    ),
    "pid": (
        "kp + ki/s + kd s/(tf_s s + 1); gains in V/m, V/(m s), V s/m",
        _per_axis_lti(lambda p: pid_tf(p.get("kp", 0.0), p.get("ki", 0.0), p.get("kd", 0.0), p.get("tf_s", 0.0))),
        ("kp", "ki", "kd", "tf_s"),
    ),
    "tf": (
        "any C(s) = num/den (coefficients, highest power first) on the error, V/m",
        _per_axis_lti(lambda p: SisoTf(p["num"], p["den"])),
        ("num", "den"),
    ),
    "cascade": (
        "position P/PI around velocity P/PI: v_ref = (kp_pos + ki_pos/s) e + velocity_ref_ff "
        "ref_vel (1/s, 1/s^2), u = (kp_vel + ki_vel/s)(v_ref - vel) (V s/m, V/m)",
        _each_axis(_cascade),
        ("kp_pos", "ki_pos", "kp_vel", "ki_vel", "velocity_ref_ff"),
    ),
    "lure": (
        "Lur'e: u = num/den (V/m) of f(error), f = nonlinearity: saturation (limit, m), dead_zone "
        "(width, m) or cosh_gain (k 1/m, e_max m)",
        _each_axis(_generic_lure),
        ("num", "den", "nonlinearity", "limit", "width", "k", "e_max"),
    ),
    "relay": (
        "relay with hysteresis on the error for the relay tuning test: u = +-amplitude_V (default 1 V), "
        "switching when the error leaves +-hysteresis_m (default 0 m)",
        _each_axis(
            lambda p, ctx, a: relay_feedback(
                p.get("amplitude_V", 1.0), p.get("hysteresis_m", 0.0), ctx.dt, a, f"relay.{a}"
            )
        ),
        ("amplitude_V", "hysteresis_m"),
    ),
    "seed003_cascade": (
        "seed 003's cascade: velocity PI for GM 9.37 dB and PM 56.4 deg, position P for PM "
        "67.1 deg (thesis Figs. 4.3, 4.7), designed on the machine's model with its delay and "
        "the encoder's backward-difference velocity; velocity_ref_ff (default 0: the thesis "
        "states none) feeds the reference velocity into the velocity loop",
        _each_axis(_seed003_cascade),
        ("velocity_ref_ff",),
    ),
    "seed004_mimo": (
        "seed 004's MIMO H-infinity loop-shaping controller (Glover-McFarlane, Ws = diag(990, 660) "
        "(s+110)/(s+1500), positions in mm), balanced-truncated to order 4 (order = 'full': 8), on "
        "axes x and y together, with ZPETC feedforward (zpetc, default true); designed on first use",
        _seed004("mimo"),
        ("zpetc", "order"),
    ),
    "seed004_pid": (
        "a PID per axis for seed 004's SISO comparison, designed here (the paper gives no gains): "
        "tuning = 'loop_at_input' (default: the crossover and phase margin of the MIMO loop broken at "
        "that input, integral corner a decade below) or 'mimo_diagonal' (the MIMO diagonal loop's "
        "crossover, kp = the MIMO controller's static gain); ki_scale multiplies the integral gain; "
        "ZPETC feedforward (zpetc, default true)",
        _seed004("pid"),
        ("zpetc", "order", "tuning", "ki_scale"),
    ),
    "seed001": (
        "seed 001's designs on the sabau_xy axes (design = "
        + ", ".join(seed001.DESIGNS)
        + "; default pi_p_pole_placement); feedforward = false drops the PI-P reference feedforward; "
        "velocity_ff = true adds the drive's velocity feedforward ref_vel/K_M (the MC206X's VFF_GAIN); "
        "ku_V_per_mm, pu_s set the ZN designs' ultimate point (default: the 10 ms-delay model's); "
        "control_period_s = 1e-3",
        _seed001,
        ("design", "feedforward", "velocity_ff", "ku_V_per_mm", "pu_s"),
    ),
    "sum": ("u = the sum of the parts' u: parts = [{ type = ... }, ...], each any kind", _sum, ()),
    "linear": (
        "any state space A, B, C, D (domain discrete or continuous) from named inputs (default "
        "['error']) to outputs (default ['u']); names without '.axis' are per axis",
        _linear,
        ("A", "B", "C", "D", "inputs", "outputs", "domain"),
    ),
}

#: Observer add-ons: name -> (description, parameter names).
OBSERVERS = {
    "inverse_model": (
        "inverse-model disturbance observer d = Q P_n^-1 pos - Q z^-m u_prev, Q = 1/(tau s + 1)^order, "
        "tau = 1/(2 pi cutoff_hz); P_n the machine's model unless num/den (m/V) are given; u_prev "
        "delayed to match delay_s (s, default the machine's drive delay)",
        ("cutoff_hz", "order", "num", "den", "delay_s"),
    ),
    "harmonic": (
        "harmonic disturbance force observer: the input disturbance's sinusoids at frequencies_hz (list), "
        "estimated from the inverse-model signal (cutoff_hz, order) with an internal model of bandwidth_hz "
        "(default 5) and predicted over the drive delay",
        ("frequencies_hz", "bandwidth_hz", "cutoff_hz", "order", "num", "den", "delay_s"),
    ),
    "inverse_model_harmonic": (
        "inverse-model observer plus the harmonic observer on what it leaves: u = u_c - d_imbdo "
        "- d_harmonic; parameters of both",
        ("frequencies_hz", "bandwidth_hz", "cutoff_hz", "order", "num", "den", "delay_s"),
    ),
}


def _check_params(name: str, params: dict, allowed) -> None:
    extra = sorted(set(params) - set(allowed))
    if extra:
        raise ValueError(f"parameter {extra[0]!r} is not one of {name}'s ({', '.join(allowed) or 'none'})")


def make_observers(name: str, params: dict, ctx: Context) -> list:
    """Observer blocks of kind ``name`` for every served axis.

    Raises
    ------
    KeyError
        Unknown name.
    ValueError
        Parameters it does not take, or values it cannot use.
    """
    if name not in OBSERVERS:
        raise KeyError(name)
    _check_params(name, params, OBSERVERS[name][1])
    for key in ("cutoff_hz", "order", "bandwidth_hz", "delay_s"):
        if key in params and not isinstance(params[key], (int, float)):
            raise ValueError(f"{key} = {params[key]!r}: must be a number")
    out: list = []
    for a in ctx.axes:
        plant = SisoTf(params["num"], params["den"]) if "num" in params else ctx.plants.get(a)
        if plant is None:
            raise ValueError(f"no nominal model for axis {a!r}: give num and den")
        cutoff, order = params.get("cutoff_hz", 100.0), params.get("order", 2)
        delay = params.get("delay_s", ctx.delay_s)
        if name in ("inverse_model", "inverse_model_harmonic"):
            out.append(
                inverse_model_observer(plant, cutoff, order, ctx.dt, a, ctx.method, name=f"observer.{a}", delay_s=delay)
            )
        if name == "harmonic":
            out.append(
                harmonic_observer(
                    plant,
                    params.get("frequencies_hz", ()),
                    params.get("bandwidth_hz", 5.0),
                    ctx.dt,
                    a,
                    ctx.method,
                    f"harmonic.{a}",
                    delay,
                    cutoff,
                    order,
                )
            )
        if name == "inverse_model_harmonic":
            # the harmonic observer compares the plant with u_prev + the inverse-model estimate of the
            # tick before (already in u_prev), so it estimates what that observer left
            previous, residual = f"harmonic.{a}:imbdo_prev.{a}", f"harmonic.{a}:u_residual.{a}"
            out += [
                Linear(
                    np.zeros((1, 1)),
                    np.ones((1, 1)),
                    np.ones((1, 1)),
                    np.zeros((1, 1)),
                    (f"observer.{a}:d_hat.{a}",),
                    (previous,),
                    name=f"imbdo_prev.{a}",
                ),
                Sum((1.0, 1.0), (f"u_prev.{a}", previous), residual, name=f"residual.{a}"),
                harmonic_observer(
                    plant,
                    params.get("frequencies_hz", ()),
                    params.get("bandwidth_hz", 5.0),
                    ctx.dt,
                    a,
                    ctx.method,
                    f"harmonic.{a}",
                    delay,
                    cutoff,
                    order,
                    u_signal=residual,
                ),
            ]
    return out


def make_controller(
    name: str,
    dt: float,
    params: dict | None = None,
    method: str = "tustin",
    velocity_ff=0.0,
    acceleration_ff=0.0,
    axes=("x",),
    plants: dict | None = None,
    parts=(),
    delay_s: float = 0.0,
) -> Controller:
    """Build a named controller for ``axes`` at period ``dt`` (s).

    ``velocity_ff``, ``acceleration_ff`` (V/(m/s), V/(m/s^2)) add reference feedforward to u;
    ``plants`` are the machine's per-axis models (m/V) and ``delay_s`` its drive delay (s), for
    model-based designs; ``parts`` are the built controllers a ``sum`` adds up.  An observer is
    added with ``with_correction(ctrl, make_observers(...))``.

    Raises
    ------
    KeyError
        Unknown name.
    ValueError
        Parameters the controller does not take, or values it cannot use.
    """
    if name not in CONTROLLERS:
        raise KeyError(name)
    _, builder, allowed = CONTROLLERS[name]
    params = dict(params or {})
    _check_params(name, params, allowed)
    ctx = Context(dt, tuple(axes), method, dict(plants or {}), list(parts), delay_s)
    ctrl = builder(params, ctx)
    ctrl.name = name
    return with_feedforward(ctrl, velocity_ff, acceleration_ff)
