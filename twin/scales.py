"""Display scales shared by recordings and plots: round numbers and the contour error
magnification."""

from __future__ import annotations

import math

import numpy as np

from twin.metrics import contour_error

_MANTISSAS = (1.0, 2.0, 5.0, 10.0)
#: Contour error magnification range.
GAIN_MIN, GAIN_MAX = 10, 1000


def round_up(x: float) -> float:
    """The smallest round number (1, 2 or 5 times a power of ten) >= ``x`` (> 0)."""
    power = 10.0 ** math.floor(math.log10(x))
    return next(m * power for m in _MANTISSAS if m * power >= x * (1 - 1e-12))


def round_down(x: float) -> float:
    """The largest round number (1, 2 or 5 times a power of ten) <= ``x`` (> 0)."""
    power = 10.0 ** math.floor(math.log10(x))
    return max(m * power for m in _MANTISSAS if m * power <= x * (1 + 1e-12))


def contour_gain(result) -> int:
    """Error magnification of a 2-D contour: the largest round number from 10 to 1000 that draws
    the worst contour error at most 10 % of the path's size."""
    pos = result.table_position_m()
    ref = result.ref[:, :, 0]
    size = np.ptp(ref, axis=0).max()
    worst = contour_error(pos[:: max(1, len(pos) // 2000)], ref).max()
    if not (worst > 0 and size > 0):
        return GAIN_MIN
    return int(min(max(round_down(0.1 * size / worst), GAIN_MIN), GAIN_MAX))
