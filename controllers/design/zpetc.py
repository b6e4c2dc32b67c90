"""Zero phase error tracking controller (Tomizuka 1987), as a filter on the reference preview.

Not in python-control or slycot, so written here.  For a discrete closed loop
``T(z^-1) = z^-d B(z^-1) / A(z^-1)`` whose zeros split into acceptable ones (``B_a``, inside
the unit circle away from it) and unacceptable ones (``B_u``, ``s`` of them), the ZPETC sends
the loop the modified reference

    r'(k) = A(z^-1) B_u(z) / (B_a(z^-1) B_u(1)^2) y_d(k + d),

which makes ``y/y_d = B_u(z^-1) B_u(z) / B_u(1)^2``: zero phase at every frequency and unit
gain at DC.  With ``B_u(z) = z^s B_u*(z^-1)`` (``B_u*`` the reversed polynomial) it is the
causal filter ``A B_u* / (B_a B_u(1)^2)`` applied to the reference ``d + s`` ticks ahead, which
is how the controller reads it from the signal bus (``preview.<axis>.<d + s>``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Zpetc:
    """A ZPETC: ``r'[k] = (num(z^-1) / den(z^-1)) y_d[k + preview]``.

    Attributes
    ----------
    num, den : tuple of float
        Coefficients in ascending powers of ``z^-1``; ``den[0] = 1``.
    preview : int
        Ticks of reference preview it needs, ``d + s``.
    delay : int
        The loop's delay ``d`` (ticks) and ``unacceptable`` its zeros that are not inverted.
    """

    num: tuple[float, ...]
    den: tuple[float, ...]
    preview: int
    delay: int
    unacceptable: tuple[complex, ...]

    def response(self, loop_num, loop_den, omega_dt) -> np.ndarray:
        """Frequency response of ``T F`` at ``omega_dt = w dt`` (rad per tick): the loop
        ``loop_num/loop_den`` (ascending powers of ``z^-1``) behind this filter."""
        zi = np.exp(-1j * np.asarray(omega_dt, float))
        poly = np.polynomial.polynomial.polyval
        filt = poly(zi, self.num) / poly(zi, self.den) * zi ** (-self.preview)
        return poly(zi, loop_num) / poly(zi, loop_den) * filt


def damping_ratio(z: complex) -> float:
    """Damping ratio of the continuous root ``s = ln z`` that a discrete root ``z`` samples:
    ``-ln|z| / |ln z|`` (1 on the positive real axis, 0 on the unit circle)."""
    s = np.log(complex(z))
    return float(-s.real / abs(s)) if abs(s) > 0 else 1.0


def zpetc(loop_num, loop_den, radius: float = 0.95, min_damping: float = 0.5) -> Zpetc:
    """ZPETC of the discrete SISO closed loop ``loop_num(z^-1) / loop_den(z^-1)``.

    Parameters
    ----------
    loop_num, loop_den : array_like
        Coefficients in ascending powers of ``z^-1``; leading zeros of ``loop_num`` are the
        delay ``d``.
    radius, min_damping : float
        Zeros on or outside the unit circle, and zeros with ``|z| >= radius`` whose damping ratio
        (:func:`damping_ratio`) is below ``min_damping`` (close to the circle and lightly damped,
        such as those near z = -1: their inverses ring), are unacceptable and not inverted.  A
        well-damped zero near z = +1 (a PI's slow zero) is inverted: keeping it would divide
        the filter by ``B_u(1)^2``, nearly zero.

    Raises
    ------
    ValueError
        A loop without any zero-free gain (numerator all zero) or with ``den[0] = 0``.
    """
    num = np.trim_zeros(np.asarray(loop_num, float), "b")
    den = np.trim_zeros(np.asarray(loop_den, float), "b")
    if not np.any(num) or den.size == 0 or den[0] == 0:
        raise ValueError("ZPETC needs a loop with a non-zero numerator and den[0] != 0")
    d = int(np.argmax(num != 0))
    b = num[d:]
    zeros = np.roots(b)  # b(z^-1) = b0 prod(1 - z_i z^-1): roots of b0 z^m + b1 z^(m-1) + ...
    unacceptable = np.array(
        [abs(z) >= 1.0 or (abs(z) >= radius and damping_ratio(z) < min_damping) for z in zeros], bool
    )
    bad, good = zeros[unacceptable], zeros[~unacceptable]
    b_a = b[0] * np.atleast_1d(np.real(np.poly(good)))  # ascending powers of z^-1: poly gives [1, -sum, ...]
    b_u = np.atleast_1d(np.real(np.poly(bad)))  # B_u(z^-1) = prod(1 - z_i z^-1), ascending in z^-1
    b_u_reversed = b_u[::-1]  # B_u*(z^-1): B_u(z) = z^s B_u*(z^-1)
    gain = float(np.sum(b_u)) ** 2  # B_u(1)^2
    filt_num = np.convolve(den, b_u_reversed) / gain / b_a[0]
    filt_den = b_a / b_a[0]
    return Zpetc(tuple(filt_num), tuple(filt_den), d + len(bad), d, tuple(complex(z) for z in bad))
