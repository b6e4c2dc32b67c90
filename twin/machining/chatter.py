"""Chatter in a run: how much the cut regenerates, read from the milling kernels' vibration probe.

In a stable cut the tool and the workpiece vibrate at the tooth-passing frequency and its
harmonics, forced by the cut; that vibration is the same one tooth period later, so it cancels
out of the once-per-tooth-period difference of their relative position, and the chip vector
(:func:`twin.machining.cutting._chips`) is the planned feed per tooth.  Regenerative chatter
vibrates at a frequency that is not a tooth harmonic, which the difference keeps.  Every physics
step that cuts, the kernels add to the probe (:data:`twin.machining.cutting.PROBE`) the square of
that difference less the planned feed per tooth, along and across the feed (mm^2), its sign
changes, and the square of the planned feed per tooth; the runner sums it per recorded tick.

The indicator of a stretch of the run is the median, over its windows of :data:`WINDOW_S`, of
the difference's RMS relative to the planned feed per tooth; over :data:`CHATTER_THRESHOLD` (a
quarter of the feed per tooth) the stretch chatters.  In chatter the teeth leave the cut
(h < 0) and the vibration grows to the order of the feed per tooth: indicators from about 0.5.
The chatter frequency is from the sign changes of the difference along the direction where it
is largest, at the physics rate (no aliasing by the recorded ticks): ``crossings / (2 time)``,
the median over the windows that chatter.  Milling chatter carries the frequencies
``f_c + k f_tooth``; the sign changes give the strongest of them.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from twin.machining.cutting import PROBE_CROSS_U, PROBE_CROSS_W, PROBE_FEED2, PROBE_STEPS, PROBE_U2, PROBE_W2
from twin.records import ChatterCheck

#: Indicator over which a stretch of a run chatters: the vibration's once-per-tooth difference
#: at a quarter of the feed per tooth (RMS).
CHATTER_THRESHOLD = 0.25
#: Length of the windows the indicator is the median over (s).
WINDOW_S = 0.02
#: A window counts when the tool cut for at least this share of it.
MIN_CUT_SHARE = 0.5


@dataclass(frozen=True)
class ChatterReading:
    """The chatter of a stretch of a run.

    Attributes
    ----------
    indicator : float
        Median over the windows of RMS(once-per-tooth vibration difference) / RMS(planned feed
        per tooth).
    chatter_hz : float or None
        The vibration's frequency in the windows that chatter (Hz); None where the stretch does
        not chatter.
    windows : int
        Windows read (those the tool cut for at least :data:`MIN_CUT_SHARE` of).
    """

    indicator: float
    chatter_hz: float | None
    windows: int

    @property
    def chatters(self) -> bool:
        """Whether the indicator is over :data:`CHATTER_THRESHOLD`."""
        return self.indicator > CHATTER_THRESHOLD

    def check(self) -> ChatterCheck:
        """The reading as the run reports it (:class:`twin.records.ChatterCheck`)."""
        return ChatterCheck(
            indicator=round(self.indicator, 4),
            chatters=self.chatters,
            chatter_hz=None if self.chatter_hz is None else round(self.chatter_hz, 1),
            threshold=CHATTER_THRESHOLD,
            windows=self.windows,
        )


def windows(probe: np.ndarray, steps_per_row: int, rows_per_window: int) -> np.ndarray:
    """The probe summed over windows of ``rows_per_window`` rows, those the tool cut for at
    least :data:`MIN_CUT_SHARE` of, shape (n, len(PROBE)).

    Parameters
    ----------
    probe : ndarray (rows, len(PROBE))
        The probe summed per recorded row.
    steps_per_row : int
        Physics steps per row (steps per tick times ticks per row).
    rows_per_window : int
    """
    rows = probe.shape[0]
    if rows == 0:
        return np.zeros((0, probe.shape[1]))
    starts = np.arange(0, rows, max(rows_per_window, 1))
    sums = np.add.reduceat(probe, starts, axis=0)
    span = np.diff(np.append(starts, rows)) * steps_per_row
    keep = (sums[:, PROBE_STEPS] >= MIN_CUT_SHARE * span) & (sums[:, PROBE_FEED2] > 0.0)
    return sums[keep]


def ratios(sums: np.ndarray) -> np.ndarray:
    """Per window (:func:`windows`): the RMS of the once-per-tooth vibration difference over
    that of the planned feed per tooth (1)."""
    return np.sqrt((sums[:, PROBE_U2] + sums[:, PROBE_W2]) / sums[:, PROBE_FEED2])


def frequency_hz(sums: np.ndarray, timestep_s: float) -> float:
    """The vibration difference's frequency over windows (:func:`windows`), from its sign
    changes along the direction (along or across the feed) where it is largest:
    ``crossings / (2 time)`` (Hz)."""
    along = sums[:, PROBE_U2].sum() >= sums[:, PROBE_W2].sum()
    crossings = sums[:, PROBE_CROSS_U if along else PROBE_CROSS_W].sum()
    return float(crossings / (2.0 * sums[:, PROBE_STEPS].sum() * timestep_s))


def chatter_reading(
    probe: np.ndarray, steps_per_row: int, row_period_s: float, timestep_s: float
) -> ChatterReading | None:
    """The chatter of a stretch of a run's probe rows (see the module docstring); None where
    the tool did not cut for a window's worth.

    Parameters
    ----------
    probe : ndarray (rows, len(PROBE))
    steps_per_row : int
        Physics steps per row.
    row_period_s : float
        Time from one row to the next (s).
    timestep_s : float
        The physics step (s).
    """
    rows_per_window = max(1, round(WINDOW_S / row_period_s))
    sums = windows(probe, steps_per_row, min(rows_per_window, len(probe)))
    if not len(sums):
        return None
    ratio = ratios(sums)
    indicator = float(np.median(ratio))
    chattering = ratio > CHATTER_THRESHOLD
    hz = frequency_hz(sums[chattering], timestep_s) if indicator > CHATTER_THRESHOLD else None
    return ChatterReading(indicator, hz, len(sums))


def rolling_indicator(probe: np.ndarray, row_period_s: float) -> np.ndarray:
    """At each probe row, the indicator over the :data:`WINDOW_S` up to it (trailing window):
    RMS of the once-per-tooth vibration difference over that of the planned feed per tooth; 0
    where the tool did not cut in the window, shape (rows,)."""
    rows = max(1, round(WINDOW_S / row_period_s))
    sums = np.cumsum(probe, axis=0)
    past = np.vstack([np.zeros((rows, probe.shape[1])), sums[:-rows]]) if len(sums) > rows else np.zeros_like(sums)
    window = sums - past[: len(sums)]
    feed = window[:, PROBE_FEED2]
    vibration = window[:, PROBE_U2] + window[:, PROBE_W2]
    return np.sqrt(np.divide(vibration, feed, out=np.zeros_like(feed), where=feed > 0.0))
