"""Transfer functions and state spaces for the run path, in plain numpy.

A run builds its controllers and observers from these, so that ``twin run`` does not import
python-control (about 2 s of start-up: it loads scipy.signal and matplotlib).  The design
procedures and fidelity checks keep using python-control; :meth:`SisoTf.to_control` hands a
model over, and :func:`state_space` takes python-control models too.

Realization and discretization follow scipy: ``tf2ss``'s controllable canonical form,
``cont2discrete``'s bilinear (Tustin) and zero-order-hold formulas.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

#: Largest degree of a transfer function's denominator: a realization of order n is an n x n
#: matrix run every tick, and canonical forms of higher order lose all precision anyway.
MAX_ORDER = 100


def _listing(coefficients, most: int = 6) -> str:
    """Coefficients as a short list for messages: ``[1, 163, 193.3]``, ``[1, 2, ... 9 more]``."""
    values = [f"{float(c):g}" if isinstance(c, (int, float, np.number)) else repr(c) for c in coefficients]
    shown = values[:most] + ([f"... {len(values) - most} more"] if len(values) > most else [])
    return "[" + ", ".join(shown) + "]"


@dataclass(frozen=True, init=False)
class SisoTf:
    """Continuous-time SISO transfer function ``num(s)/den(s)``.

    Attributes
    ----------
    num, den : tuple of float
        Polynomial coefficients, highest power of s first; the units are those of the model
        (for example m/V for a plant, V/m for a controller).

    Raises
    ------
    ValueError
        Empty or nested lists, an all-zero denominator, a degree above :data:`MAX_ORDER`, or
        coefficients that are not finite (also after dividing by the leading denominator
        coefficient).
    """

    num: tuple[float, ...]
    den: tuple[float, ...]

    def __init__(self, num: ArrayLike, den: ArrayLike) -> None:
        try:
            num, den = (np.atleast_1d(np.asarray(c, float)) for c in (num, den))
        except (TypeError, ValueError):
            raise ValueError("transfer function coefficients must be numbers") from None
        if num.ndim != 1 or den.ndim != 1 or num.size == 0:
            raise ValueError("transfer function coefficients must be non-empty flat lists")
        name = f"transfer function {_listing(num)}/{_listing(den)}"
        num, den = np.trim_zeros(num, "f"), np.trim_zeros(den, "f")
        if den.size == 0:
            raise ValueError(f"{name}: the denominator is zero")
        if den.size - 1 > MAX_ORDER:
            raise ValueError(f"{name}: degree {den.size - 1} above the limit of {MAX_ORDER}")
        with np.errstate(over="ignore", invalid="ignore"):
            normalized = np.concatenate([num, den]) / den[0]
        if not np.isfinite(normalized).all():
            raise ValueError(f"{name}: coefficients must be finite, also divided by den[0] = {den[0]:g}")
        object.__setattr__(self, "num", tuple(float(c) for c in num) or (0.0,))
        object.__setattr__(self, "den", tuple(float(c) for c in den))

    @property
    def relative_degree(self) -> int:
        """deg(den) - deg(num); negative for an improper model."""
        return len(self.den) - len(self.num)

    def __call__(self, s):
        """Value at the complex frequency ``s`` (rad/s), e.g. ``g(2j * pi * f)``."""
        return np.polyval(self.num, s) / np.polyval(self.den, s)

    def to_control(self):
        """The same model as a ``control.TransferFunction`` (imports python-control)."""
        import control

        return control.tf(list(self.num), list(self.den))


def tf_to_ss(tf: SisoTf) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Controllable canonical realization ``(A, B, C, D)`` of a proper SISO model.

    Raises
    ------
    ValueError
        Improper model (more zeros than poles).
    """
    if tf.relative_degree < 0:
        raise ValueError(
            f"transfer function {_listing(tf.num)}/{_listing(tf.den)} is improper "
            f"(numerator degree above the denominator's)"
        )
    den = np.asarray(tf.den) / tf.den[0]
    n = len(den) - 1
    num = np.concatenate([np.zeros(n + 1 - len(tf.num)), tf.num]) / tf.den[0]
    A = np.zeros((n, n))
    if n:
        A[0] = -den[1:]
        A[1:, :-1] = np.eye(n - 1)
    B = np.zeros((n, 1))
    if n:
        B[0, 0] = 1.0
    with np.errstate(over="ignore", invalid="ignore"):  # non-finite entries: Linear names the block
        C = (num[1:] - num[0] * den[1:]).reshape(1, n)
    D = np.array([[num[0]]])
    return A, B, C, D


def discretize(A, B, C, D, *, dt: float, method: str = "tustin"):
    """Discrete equivalent at period ``dt`` (s) of a continuous state space.

    ``method`` is ``"tustin"`` (bilinear) or ``"zoh"`` (zero-order hold, exact for piecewise
    constant inputs; imports scipy.linalg for the matrix exponential).

    Non-finite entries of the result (a model too stiff for ``dt``) are left for the caller
    (:class:`~controllers.blocks.core.Linear` rejects them, naming the block).

    Raises
    ------
    ValueError
        Unknown method, or a Tustin map that is singular (a pole at ``s = 2/dt``).
    """
    with np.errstate(over="ignore", invalid="ignore"):  # non-finite results are the caller's to report
        A2, B2, C2, D2 = (np.atleast_2d(np.asarray(m, float)) for m in (A, B, C, D))
        return _discretize(A2, B2, C2, D2, dt=dt, method=method)


def _discretize(A, B, C, D, *, dt, method):
    n, m = B.shape
    if method == "tustin":
        if n == 0:
            return A, B, C, D
        left = np.eye(n) - 0.5 * dt * A
        try:
            Ad = np.linalg.solve(left, np.eye(n) + 0.5 * dt * A)
            Bd = np.linalg.solve(left, dt * B)
            Cd = np.linalg.solve(left.T, C.T).T
        except np.linalg.LinAlgError:
            raise ValueError(f"Tustin at dt = {dt:g} s is singular: the model has a pole at s = 2/dt") from None
        return Ad, Bd, Cd, D + 0.5 * C @ Bd
    if method == "zoh":
        from scipy.linalg import expm

        big = np.zeros((n + m, n + m))
        big[:n, :n], big[:n, n:] = A * dt, B * dt
        e = expm(big)
        return e[:n, :n], e[:n, n:], C, D
    raise ValueError(f"method = {method!r}: use 'tustin' or 'zoh'")


def step_from_rest(sys, *, dt: float, n: int) -> np.ndarray:
    """Unit step response from rest of a continuous SISO model at ``t = 0, dt, ... (n-1) dt`` (s).

    Exact at the samples (the step is constant between them): the zero-order-hold states
    ``x[k] = sum_{j<k} Ad^j Bd``, built by doubling, ``x[k + m] = Ad^m x[k] + x[m]`` (a dozen
    matrix products for thousands of samples, where a sample-by-sample loop takes one
    Python step each).

    Parameters
    ----------
    sys
        A continuous model :func:`state_space` takes, one input and one output.
    dt : float
        Sample period (s).
    n : int
        Samples, ``t = 0`` first.

    Returns
    -------
    ndarray (n,)
        The output.
    """
    A, B, C, D, sample_time = state_space(sys)
    if sample_time is not None or B.shape[1] != 1 or C.shape[0] != 1:
        raise ValueError("step_from_rest: needs a continuous model with one input and one output")
    Ad, Bd, _, _ = discretize(A, B, C, D, dt=dt, method="zoh")
    x = np.zeros((n, A.shape[0]))
    if n > 1:
        x[1] = Bd[:, 0]
    m, power = 1, Ad  # x[: m + 1] known; power = Ad^m
    while m + 1 < n:
        count = min(m, n - 1 - m)
        x[m + 1 : m + 1 + count] = x[1 : 1 + count] @ power.T + x[m]
        m, power = 2 * m, power @ power
    return x @ C[0] + D[0, 0]


def state_space(sys):
    """``(A, B, C, D, dt)`` of a model; ``dt`` is None for continuous ones.

    ``sys`` is a :class:`SisoTf`, a tuple ``(A, B, C, D)`` of continuous matrices, or a
    python-control LTI model (continuous or discrete).
    """
    if isinstance(sys, SisoTf):
        return (*tf_to_ss(sys), None)
    if isinstance(sys, tuple):
        return (*(np.atleast_2d(np.asarray(m, float)) for m in sys), None)
    import control  # a python-control model: the library is loaded already

    ss = control.ss(sys)
    return ss.A, ss.B, ss.C, ss.D, (None if ss.isctime() else ss.dt)


def delay_ticks(n: int):
    """Discrete ``z^-n`` as ``(A, B, C, D)`` (a shift register of ``n`` states)."""
    A = np.eye(n, k=-1)
    B = np.zeros((n, 1))
    C = np.zeros((1, n))
    if n:
        B[0, 0], C[0, -1] = 1.0, 1.0
    return A, B, C, np.array([[0.0 if n else 1.0]])


def series(first, second):
    """``second(first(v))`` of two state spaces ``(A, B, C, D)`` (same sampling)."""
    A1, B1, C1, D1 = first
    A2, B2, C2, D2 = second
    n1, n2 = A1.shape[0], A2.shape[0]
    A = np.block([[A1, np.zeros((n1, n2))], [B2 @ C1, A2]])
    return A, np.vstack([B1, B2 @ D1]), np.hstack([D2 @ C1, C2]), D2 @ D1


def summed_inputs(*systems):
    """One state space whose inputs are all the systems' inputs, side by side, and whose
    output is the sum of their outputs (``y = G1 v1 + G2 v2 + ...``)."""
    n = [s[0].shape[0] for s in systems]
    m = [s[1].shape[1] for s in systems]
    A = np.zeros((sum(n), sum(n)))
    B = np.zeros((sum(n), sum(m)))
    r = c = 0
    for (Ai, Bi, _, _), ni, mi in zip(systems, n, m):
        A[r : r + ni, r : r + ni] = Ai
        B[r : r + ni, c : c + mi] = Bi
        r, c = r + ni, c + mi
    return A, B, np.hstack([s[2] for s in systems]), np.hstack([s[3] for s in systems])
