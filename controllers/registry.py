"""Controllers by name, as scenario files and the CLI refer to them."""

from __future__ import annotations

import control

from controllers import seed000, seed002
from controllers.lti import DiscreteLTI
from controllers.pid import pid_tf

#: name -> (description, builder(params) -> continuous LTI, allowed parameter names)
CONTROLLERS = {
    "seed000_robust_pi": ("robust PI 38.33 + 45.65/s, seed 000 eqs. (18)-(19)",
                          lambda p: seed000.ROBUST_PI, ()),
    "seed000_imc": ("IMC (0.21 s + 2)/(s + 2), seed 000 eq. (23)", lambda p: seed000.IMC, ()),
    "seed000_hinf": ("full 4th-order H-infinity, seed 000 eq. (28)", lambda p: seed000.HINF, ()),
    "seed000_hinf_reduced": ("reduced H-infinity 20.97/(s + 5.5), seed 000 eq. (29)",
                             lambda p: seed000.HINF_REDUCED, ()),
    "seed002_pid": ("PID 0.8998 + 0.005155 s + 0.0006077/s (V/mm), seed 002 eq. (6); derivative "
                    "filter tf_s (default 1e-4 s)",
                    lambda p: seed002.pid(p.get("tf_s", 1e-4)), ("tf_s",)),
    "pid": ("kp + ki/s + kd s/(tf_s s + 1); gains in V/m, V/(m s), V s/m",
            lambda p: pid_tf(p.get("kp", 0.0), p.get("ki", 0.0), p.get("kd", 0.0), p.get("tf_s", 0.0)),
            ("kp", "ki", "kd", "tf_s")),
    "tf": ("any C(s) = num/den (coefficients, highest power first), V/m",
           lambda p: control.tf(p["num"], p["den"]), ("num", "den")),
}


def make_controller(name: str, dt: float, params: dict | None = None, method: str = "tustin",
                    velocity_ff: float = 0.0, acceleration_ff: float = 0.0) -> DiscreteLTI:
    """Build a named controller as a :class:`DiscreteLTI` block at period ``dt`` (s).

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
    extra = sorted(set(params) - set(allowed))
    if extra:
        raise ValueError(f"parameter {extra[0]!r} is not one of {name}'s ({', '.join(allowed) or 'none'})")
    return DiscreteLTI(builder(params), dt, method, velocity_ff, acceleration_ff, name=name)
