"""Performance metrics of responses and tracking runs.

Step metrics follow the usual definitions, stated per function: overshoot relative to the
final value, 2 % settling time, 10-90 % rise time and the 0-100 % rise time (first time the
response reaches its final value), which some papers call rise time.
"""

from __future__ import annotations

import numpy as np


def step_metrics(t_s: np.ndarray, y: np.ndarray, final: float | None = None,
                 settling_band: float = 0.02) -> dict[str, float]:
    """Overshoot, settling and rise times of a step response.

    Parameters
    ----------
    t_s : ndarray, shape (n,)
        Time (s), step applied at ``t_s[0]``.
    y : ndarray, shape (n,)
        Response, starting from 0.
    final : float, optional
        Final value; default the last sample.
    settling_band : float
        Settling band as a fraction of ``final`` (0.02 for 2 %).

    Returns
    -------
    dict
        ``overshoot_pct`` (%, 0 if none), ``settling_time_s`` (last exit from the band),
        ``rise_time_10_90_s``, ``rise_time_0_100_s`` (nan if never reached), ``peak``,
        ``final``.
    """
    t = np.asarray(t_s, float) - t_s[0]
    y = np.asarray(y, float)
    yf = float(y[-1] if final is None else final)
    peak = float(y.max() if yf >= 0 else y.min())
    overshoot = max(0.0, (peak - yf) / abs(yf) * 100.0) if yf else float("nan")
    outside = np.flatnonzero(np.abs(y - yf) > settling_band * abs(yf))
    if outside.size == 0:
        settling = 0.0
    elif outside[-1] + 1 < len(t):
        settling = float(t[outside[-1] + 1])
    else:
        settling = float("nan")

    def first_cross(level):
        idx = np.flatnonzero(y >= level) if yf >= 0 else np.flatnonzero(y <= level)
        if idx.size == 0:
            return float("nan")
        i = idx[0]
        if i == 0:
            return float(t[0])
        # linear interpolation between samples
        return float(t[i - 1] + (level - y[i - 1]) / (y[i] - y[i - 1]) * (t[i] - t[i - 1]))

    return {
        "overshoot_pct": overshoot,
        "settling_time_s": settling,
        "rise_time_10_90_s": first_cross(0.9 * yf) - first_cross(0.1 * yf),
        "rise_time_0_100_s": first_cross(yf),
        "peak": peak,
        "final": yf,
    }


def contour_error(actual_xy: np.ndarray, path_xy: np.ndarray) -> np.ndarray:
    """Distance (same unit) from each actual point to the reference path.

    Parameters
    ----------
    actual_xy : ndarray, shape (n, 2)
    path_xy : ndarray, shape (m, 2)
        Densely sampled reference path, treated as a polyline.

    Returns
    -------
    ndarray, shape (n,)
        Shortest distance from every actual point to the polyline's segments.
    """
    p = np.asarray(actual_xy, float)
    a = np.asarray(path_xy, float)[:-1]
    b = np.asarray(path_xy, float)[1:]
    ab = b - a
    len2 = np.maximum((ab**2).sum(1), 1e-300)
    out = np.empty(len(p))
    for start in range(0, len(p), 512):  # bounded memory: 512 x segments at a time
        q = p[start:start + 512, None, :]
        s = np.clip(((q - a) * ab).sum(-1) / len2, 0.0, 1.0)
        d = np.linalg.norm(q - (a + s[..., None] * ab), axis=-1)
        out[start:start + 512] = d.min(axis=1)
    return out


def tracking_summary(result) -> dict:
    """Max and RMS tracking error per axis (um) and the largest cutting force per axis (N,
    tick means, when there is one), all over every tick of the run; for 2-D paths, max and RMS
    contour error (um) over the recorded ticks (none when only metrics were kept)."""
    out = {
        "max_tracking_error_um": dict(zip(result.axis_names, (result.error_max_m * 1e6).round(3).tolist())),
        "rmse_um": dict(zip(result.axis_names, (result.error_rms_m * 1e6).round(3).tolist())),
    }
    if result.force_max_N.any():  # cutting: tick-mean force on the workpiece along each axis
        out["max_cutting_force_N"] = dict(zip(result.axis_names, result.force_max_N.round(1).tolist()))
    ref = result.ref[:, :, 0]
    if ref.shape[1] == 2 and len(ref) > 1 and (np.ptp(ref, axis=0) > 0).all():  # a 2-D path
        ce = contour_error(result.table_position_m(), ref)
        out["max_contour_error_um"] = round(float(ce.max() * 1e6), 3)
        out["rms_contour_error_um"] = round(float(np.sqrt(np.mean(ce**2)) * 1e6), 3)
    return out
