"""Stability of milling against regenerative chatter: the critical axial depth against the
spindle speed (stability lobes), by two methods.

The cut is the twin's own (:mod:`twin.machining.cutting`, Altintas, *Manufacturing Automation*,
2nd ed., ch. 2.5 and 3.4): in the feed frame (x along the feed, y = z x feed), flute ``j`` at
immersion angle ``phi_j`` (clockwise from y) engaged on ``[phi_st, phi_ex]`` takes the dynamic
chip ``h = dx sin(phi) + dy cos(phi)`` with ``d = q(t) - q(t - T)`` the tool's displacement
relative to the workpiece now less one tooth period ``T = 60 / (N n)`` ago, and pushes the tool
with ``F_x = -F_t cos(phi) - F_r sin(phi)``, ``F_y = F_t sin(phi) - F_r cos(phi)``, ``F_t =
K_t a h``, ``F_r = K_r F_t``.  So ``F = a H(t) d`` with the periodic matrix (N/m^2)

``H = K_t sum_j g_j [[-(sin c + K_r sin^2), -(cos^2 + K_r sin c)], [sin^2 - K_r sin c, sin c -
K_r cos^2]]`` (``sin``, ``cos`` of ``phi_j``, ``c = cos(phi_j)``, ``g_j`` 1 in the cut).

Zero-order approximation (:func:`zoa_critical_depths`; Altintas and Budak, CIRP Annals 44
(1995) 357-362)
    ``H`` replaced by its mean ``H0 = N/(2 pi) int H dphi`` (the paper's ``K_t [A0] / 2``), the
    chatter condition ``det(I - a (1 - exp(-i w T)) H0 G(i w)) = 0`` (``G`` the relative
    receptance).  With ``lambda`` an eigenvalue of ``H0 G`` and ``nu = 1/lambda``: ``a = |nu|^2 /
    (2 Re nu)`` where ``Re nu > 0``, and ``w T = pi - 2 arg(nu) + 2 pi k`` (the paper's eqs. 20-23
    with ``Lambda = -2 nu / (N K_t ...)``, written without its constants).  For each spindle speed
    the lowest depth over every chatter frequency and lobe ``k`` is the critical one.
Semi-discretization (:func:`sd_critical_depths`; Insperger and Stepan, Int. J. Numer. Meth.
Eng. 55 (2002) 503-518 and 61 (2004) 117-141, the first-order form)
    The modal model ``y' = A(t) y + B(t) x(t - T)`` with ``A = A0 + a Bf H(t) C``, ``B = -a Bf
    H(t)``; the tooth period in ``m`` steps, ``H`` averaged over each, the delayed position
    interpolated linearly between its two grid values, each step solved exactly (one matrix
    exponential of the augmented system).  The monodromy matrix of one period: the cut is stable
    while its spectral radius is under 1.  The depths are scanned on a grid, and the first
    unstable one refined by bisection.

Both ignore the helix (its effect on the zero-order solution is nil, on the semi-discretization
small for depths under the helix pitch) and the edge forces (no chip regeneration).
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass

import numpy as np

from twin.errors import TwinInputError
from twin.machining.tool_dynamics import DIRECTIONS, ToolDynamicsSpec, feed_frame_rotation

#: Frequency points of the zero-order solution at most (memory and time are bounded).
MAX_FREQUENCIES = 200_000
#: Relative step of the zero-order frequency grid per damping ratio (an 80th of a mode's half
#: power band width, 2 zeta: the lobes' cusps, where two lobes cross steeply, need it).
FREQUENCY_STEP_PER_ZETA = 0.025
#: Speeds times chatter frequencies the zero-order solution holds at once.
ZOA_CELLS = 2_000_000
#: Grid points per spindle speed and depth at most in one batch of the semi-discretization.
SD_BATCH = 4000
#: Bisection steps refining the semi-discretization's first unstable depth.
SD_BISECTIONS = 8
#: Secant steps of the semi-discretization's finer boundary.
SD_SECANTS = 4
#: How near 1 the finer boundary's spectral radius must come.
SD_RADIUS_TOLERANCE = 2e-4
#: Steps per period of the highest mode at least (the semi-discretization's resolution).
SD_STEPS_PER_CYCLE = 3.0
#: Steps in the cut per tooth period at most (the finer boundary takes :data:`SD_FINER` times as many).
SD_MAX_STEPS = 40
#: The finer boundary's steps over the coarser's (Richardson's ratio).
SD_FINER = 1.5
#: Depths the semi-discretization scans at a time, upwards.
SD_SCAN = 10
#: Speeds of one lobe computation at most.
MAX_SPEEDS = 10_000


@dataclass(frozen=True)
class Cut:
    """A milling cut's regenerative force: ``N`` flutes, tangential cutting coefficient
    ``K_t`` (N/m^2), ``K_r = K_rc/K_tc``, the engaged arcs ``(phi_st, phi_ex)`` (rad, immersion
    angles of :func:`twin.machining.cutting.immersion_angles`) each with its share of the axial
    depth (1 for a single arc), and the feed's angle from the machine's X (rad)."""

    n_flutes: int
    K_t: float
    K_r: float
    arcs: tuple[tuple[float, float, float], ...]
    feed_angle_rad: float = 0.0

    def tooth_period_s(self, spindle_rpm) -> np.ndarray:
        """``T = 60 / (N n)`` (s) at the speeds ``spindle_rpm``."""
        return 60.0 / (self.n_flutes * np.asarray(spindle_rpm, float))

    def mean_matrix(self) -> np.ndarray:
        """``H0`` (2, 2) in the machine's X/Y (N/m^2): the mean of ``H`` over a tooth period."""
        h0 = sum(share * _arc_integral(st, ex, self.K_r) for st, ex, share in self.arcs)
        rot = feed_frame_rotation(self.feed_angle_rad)
        return rot @ (self.K_t * self.n_flutes / (2 * math.pi) * np.asarray(h0)) @ rot.T

    def step_matrices(self, steps: int) -> tuple[np.ndarray, np.ndarray]:
        """A tooth period in steps: where a flute enters or leaves the cut a step ends, each
        stretch in the cut is split into equal steps (``steps`` in all, in proportion to their
        lengths, at least one each), each stretch out of it is one step.

        Returns
        -------
        widths : ndarray (M,)
            Each step's share of the tooth period (they sum to 1).
        h : ndarray (M, 2, 2)
            ``H`` averaged over each step, machine X/Y (N/m^2); zero out of the cut.  Flute 0
            is at angle 0 at the period's start.
        """
        pitch = 2 * math.pi / self.n_flutes
        edges = {0.0, pitch}
        for st, ex, _share in self.arcs:
            for angle in (st, ex):
                edges.add(math.fmod(angle, pitch))
        cuts = sorted(edges)
        stretches = [(a, b) for a, b in itertools.pairwise(cuts) if b - a > 1e-12]
        engaged = [self._engaged(0.5 * (a + b)) for a, b in stretches]
        cut_length = sum(b - a for (a, b), e in zip(stretches, engaged) if e)
        bounds = []
        for (a, b), e in zip(stretches, engaged):
            n = max(1, round(steps * (b - a) / cut_length)) if e else 1
            bounds.extend(np.linspace(a, b, n + 1)[:-1].tolist())
        bounds.append(pitch)
        grid = np.array(bounds)
        h = np.array([self._integral(lo, hi) / (hi - lo) for lo, hi in itertools.pairwise(grid)])
        rot = feed_frame_rotation(self.feed_angle_rad)
        return np.diff(grid) / pitch, rot @ (self.K_t * h) @ rot.T

    def _engaged(self, angle: float) -> bool:
        """Whether some flute is in the cut while flute 0 is at ``angle`` (rad)."""
        pitch = 2 * math.pi / self.n_flutes
        phis = [math.fmod(angle + j * pitch, 2 * math.pi) for j in range(self.n_flutes)]
        return any(st <= phi <= ex or st <= phi + 2 * math.pi <= ex for phi in phis for st, ex, _s in self.arcs)

    def _integral(self, lo: float, hi: float) -> np.ndarray:
        """``int_lo^hi sum_j H(phi + j pitch) dphi / K_t`` (2, 2), feed frame: every flute
        over the spindle angles ``lo`` to ``hi`` (rad) of flute 0."""
        pitch = 2 * math.pi / self.n_flutes
        out = np.zeros((2, 2))
        for j in range(self.n_flutes):
            for st, ex, share in self.arcs:
                for shift in (-2 * math.pi, 0.0, 2 * math.pi):
                    a, b = max(lo + j * pitch + shift, st), min(hi + j * pitch + shift, ex)
                    if b > a:
                        out += share * _arc_integral(a, b, self.K_r)
        return out


def _arc_integral(lo: float, hi: float, k_r: float) -> np.ndarray:
    """``int_lo^hi H dphi / K_t`` of one flute (2, 2), feed frame (rad)."""

    def primitive(phi):
        sc, ss = math.sin(phi) ** 2 / 2, phi / 2 - math.sin(2 * phi) / 4
        cc = phi / 2 + math.sin(2 * phi) / 4
        return np.array([[-(sc + k_r * ss), -(cc + k_r * sc)], [ss - k_r * sc, sc - k_r * cc]])

    return primitive(hi) - primitive(lo)


@dataclass(frozen=True)
class Lobes:
    """Critical axial depth (m; nan: none up to the depths searched) and the chatter frequency
    (Hz) at each spindle speed (rpm), by ``method`` ("zoa" or "sd")."""

    method: str
    spindle_rpm: np.ndarray
    critical_depth_m: np.ndarray
    chatter_hz: np.ndarray

    def records(self) -> list[dict]:
        """One dict per speed: ``spindle_rpm``, ``critical_depth_mm`` and ``chatter_hz`` (None
        where there is no boundary)."""
        out = []
        for n, a, f in zip(self.spindle_rpm, self.critical_depth_m, self.chatter_hz):
            found = bool(np.isfinite(a))
            out.append(
                {
                    "spindle_rpm": round(float(n), 3),
                    "critical_depth_mm": round(float(a) * 1e3, 5) if found else None,
                    "chatter_hz": round(float(f), 2) if found else None,
                }
            )
        return out


def frequency_grid_hz(dynamics: ToolDynamicsSpec, longest_period_s: float) -> np.ndarray:
    """The chatter frequencies the zero-order solution searches (Hz): geometric, an 80th of
    the least damped mode's half power band width apart and under ``1/(4 T)`` apart (so that
    ``w T`` moves less than half a turn a step), over the receptance's known range (modes:
    0.2 to 4 times their natural frequencies; a measured FRF: 2.5e-4 apart, relative, over its range).

    Raises
    ------
    TwinInputError
        Over :data:`MAX_FREQUENCIES` points (a very low spindle speed for its modes).
    """
    low, high = dynamics.frequency_range_hz()
    if dynamics.measured is None:
        low = 0.2 * min(m.frequency_hz for m in dynamics.modes)
        ratio = FREQUENCY_STEP_PER_ZETA * min(m.damping_ratio for m in dynamics.modes)
    else:
        ratio = 2.5e-4
    ratio = min(ratio, 1.0 / (4.0 * longest_period_s * high))
    count = math.ceil(math.log(high / low) / math.log1p(ratio)) + 1
    if count > MAX_FREQUENCIES:
        raise TwinInputError(
            "spindle_rpm",
            f"{60.0 / longest_period_s:g} teeth/min",
            f"the tool's dynamics at this speed need {count} chatter frequencies, over {MAX_FREQUENCIES}: a higher "
            "lowest speed",
        )
    return np.geomspace(low, high, count)


def zoa_critical_depths(cut: Cut, dynamics: ToolDynamicsSpec, spindle_rpm) -> Lobes:
    """Critical depth (m) and chatter frequency (Hz) at each speed by the zero-order
    approximation (module docstring).

    Parameters
    ----------
    cut : Cut
    dynamics : ToolDynamicsSpec
        The tool's structure (X/Y).
    spindle_rpm : array_like
        Speeds (rev/min, positive).
    """
    speeds = _speeds(spindle_rpm)
    periods = cut.tooth_period_s(speeds)
    freq = frequency_grid_hz(dynamics, float(periods.max()))
    depth, freq_at = zoa_boundaries(cut.mean_matrix()[None], freq, dynamics.receptance(freq), periods[None])
    return Lobes("zoa", speeds, depth[0], freq_at[0])


def zoa_boundaries(
    mean_h: np.ndarray, frequency_hz: np.ndarray, receptance: np.ndarray, periods_s: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """The zero-order critical depth (m, nan: none) and chatter frequency (Hz) of several cuts,
    each at its own tooth periods.

    Parameters
    ----------
    mean_h : ndarray (c, 2, 2)
        Each cut's mean force matrix ``H0`` (N/m^2, X/Y).
    frequency_hz, receptance : ndarray (f,), (f, 2, 2)
        The chatter frequencies searched (:func:`frequency_grid_hz`) and the relative
        receptance there (m/N).
    periods_s : ndarray (c, p)
        Tooth periods (s) per cut.
    """
    with np.errstate(all="ignore"):  # a singular or huge receptance: no boundary there, not a warning
        lam = eigenvalues_2x2(mean_h[:, None] @ receptance[None])  # (c, f, 2)
        nu = 1.0 / lam
        valid = nu.real > 0
    # only the frequencies where some cut can chatter (and their neighbours) are searched
    chatters: np.ndarray = np.asarray(valid.any(axis=(0, 2)))
    near = chatters.copy()
    near[:-1] |= chatters[1:]
    near[1:] |= chatters[:-1]
    frequency_hz, nu, valid = frequency_hz[near], nu[:, near], valid[:, near]
    if frequency_hz.size < 2:
        return np.full(periods_s.shape, np.nan), np.full(periods_s.shape, np.nan)
    with np.errstate(all="ignore"):
        depth = np.where(valid, np.abs(nu) ** 2 / (2.0 * nu.real), np.nan)
        theta = np.pi - 2.0 * np.angle(nu)  # w T less its whole turns, in (0, 2 pi)
    omega = 2 * np.pi * frequency_hz
    n_cuts, n_periods = periods_s.shape
    best = np.full((n_cuts, n_periods), np.inf)
    best_hz = np.full((n_cuts, n_periods), np.nan)
    per_chunk = max(1, min(n_periods, ZOA_CELLS // len(frequency_hz)))  # memory stays bounded
    cuts_chunk = max(1, ZOA_CELLS // (per_chunk * len(frequency_hz)))
    for c0 in range(0, n_cuts, cuts_chunk):
        cs = slice(c0, c0 + cuts_chunk)
        for p0 in range(0, n_periods, per_chunk):
            ps = slice(p0, p0 + per_chunk)
            for branch in range(nu.shape[2]):
                a_b, th_b = depth[cs, None, :, branch], theta[cs, None, :, branch]  # (c, 1, f)
                seg = valid[cs, None, :-1, branch] & valid[cs, None, 1:, branch]
                turns = (omega * periods_s[cs, ps, None] - th_b) / (2 * np.pi)  # (c, p, f)
                lo, hi = turns[..., :-1], turns[..., 1:]
                k = np.ceil(np.minimum(lo, hi))
                crosses = seg & (k <= np.maximum(lo, hi)) & (k >= 0)
                with np.errstate(all="ignore"):
                    frac = np.where(crosses, (k - lo) / (hi - lo), 0.0)
                    a_cross = np.where(crosses, a_b[..., :-1] + frac * (a_b[..., 1:] - a_b[..., :-1]), np.inf)
                where = np.argmin(a_cross, axis=2)[..., None]
                a_min = np.take_along_axis(a_cross, where, 2)[..., 0]
                f_at = np.take_along_axis(frac, where, 2)[..., 0]
                w = where[..., 0]
                f_min = frequency_hz[w] + f_at * (frequency_hz[w + 1] - frequency_hz[w])
                better = a_min < best[cs, ps]
                best[cs, ps] = np.where(better, a_min, best[cs, ps])
                best_hz[cs, ps] = np.where(better, f_min, best_hz[cs, ps])
    best[~np.isfinite(best)] = np.nan
    return best, best_hz


def eigenvalues_2x2(m: np.ndarray) -> np.ndarray:
    """Both eigenvalues of each 2 x 2 matrix of ``m`` (..., 2, 2): ``tr/2 +- sqrt(tr^2/4 - det)``."""
    half = 0.5 * (m[..., 0, 0] + m[..., 1, 1])
    det = m[..., 0, 0] * m[..., 1, 1] - m[..., 0, 1] * m[..., 1, 0]
    root = np.sqrt(half * half - det + 0j)
    return np.stack([half + root, half - root], axis=-1)


def _speeds(spindle_rpm) -> np.ndarray:
    speeds = np.atleast_1d(np.asarray(spindle_rpm, float))
    if speeds.size == 0 or speeds.size > MAX_SPEEDS or not np.all(np.isfinite(speeds)) or np.any(speeds <= 0):
        raise TwinInputError("spindle_rpm", speeds.tolist()[:5], f"1 to {MAX_SPEEDS} positive speeds")
    return speeds


@dataclass(frozen=True)
class ModalModel:
    """The tool's modes as a state-space system ``y' = A0 y + Bf F``, ``x = C y``: ``y`` the
    modal displacements and velocities, ``x`` the tip's displacement along the directions that
    have modes (``axes``: indices into X/Y), ``F`` the force along them (N)."""

    a0: np.ndarray
    bf: np.ndarray
    c: np.ndarray
    axes: tuple[int, ...]
    dominant_hz: float

    @classmethod
    def of(cls, dynamics: ToolDynamicsSpec) -> ModalModel:
        """The model of ``dynamics``' modes.

        Raises
        ------
        TwinInputError
            A measured FRF (no modes).
        """
        if dynamics.measured is not None:
            raise TwinInputError(
                "dynamics.frf_file", dynamics.frf_file, "semi-discretization needs modes (use the zoa method)"
            )
        modes = dynamics.modes
        axes = tuple(sorted({DIRECTIONS.index(m.direction) for m in modes}))
        n = len(modes)
        omega = np.array([m.omega_rad_s for m in modes])
        zeta = np.array([m.damping_ratio for m in modes])
        a0 = np.zeros((2 * n, 2 * n))
        a0[:n, n:] = np.eye(n)
        a0[n:, :n] = -np.diag(omega**2)
        a0[n:, n:] = -np.diag(2 * zeta * omega)
        shape = np.array([[1.0 if DIRECTIONS.index(m.direction) == ax else 0.0 for m in modes] for ax in axes])
        bf = np.zeros((2 * n, len(axes)))
        bf[n:] = shape.T / np.array([m.mass for m in modes])[:, None]
        c = np.zeros((len(axes), 2 * n))
        c[:, :n] = shape
        peak = max(modes, key=lambda m: 1.0 / (m.stiffness * m.damping_ratio))
        return cls(a0, bf, c, axes, peak.frequency_hz)


def expm_batch(x: np.ndarray) -> np.ndarray:
    """``exp`` of each square matrix of ``x`` (..., n, n): scaling and squaring with a
    degree-12 Taylor series (each scaled matrix's norm under 1/2: error under 1e-15)."""
    norm = np.abs(x).sum(axis=-1).max()
    squarings = max(0, math.ceil(math.log2(norm / 0.5))) if norm > 0 else 0
    scaled = x / 2.0**squarings
    out = np.broadcast_to(np.eye(x.shape[-1]), x.shape).copy()
    term = out.copy()
    for k in range(1, 13):
        term = term @ scaled / k
        out += term
    for _ in range(squarings):
        out = out @ out
    return out


def sd_spectral_radius(
    model: ModalModel, steps: tuple[np.ndarray, np.ndarray], period_s: np.ndarray, depth_m: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Spectral radius and its eigenvalue of the monodromy matrix of one tooth period, for each
    pair of ``period_s`` and ``depth_m`` (arrays of one shape ``(b,)``), by first-order
    semi-discretization.

    Parameters
    ----------
    model : ModalModel
    steps : (ndarray (M,), ndarray (M, 2, 2))
        The tooth period's steps (shares of it) and the cut's matrix averaged over each
        (:meth:`Cut.step_matrices`, N/m^2).  The grid is the same every period, so the
        position one period before a grid point is the one stored for that point.
    period_s, depth_m : ndarray (b,)
        Tooth periods (s) and axial depths (m).
    """
    widths, steps_h = steps
    m = len(widths)
    axes = list(model.axes)
    h = steps_h[:, axes][:, :, axes]  # (M, dx, dx)
    d, dx = model.a0.shape[0], len(axes)
    b = len(period_s)
    cutting = np.flatnonzero(np.abs(h).reshape(m, -1).max(axis=1) > 0)
    dt = period_s[:, None, None, None] * widths[cutting][None, :, None, None]  # (b, M_cut, 1, 1)
    # the augmented step in time / dt: d/ds [y; v; w] = [[A dt, B dt, 0], [0, 0, I], [0, 0, 0]] [y; v; w],
    # v = x(t_i - T) + s w, w = x(t_(i+1) - T) - x(t_i - T)
    size = d + 2 * dx
    aug = np.zeros((b, len(cutting), size, size))
    bfh = np.einsum("ij,mjk->mik", model.bf, h[cutting])  # (M_cut, d, dx)
    depth = depth_m[:, None, None, None]
    aug[:, :, :d, :d] = (model.a0[None, None] + depth * (bfh @ model.c)[None]) * dt
    aug[:, :, :d, d : d + dx] = -depth * bfh[None] * dt
    aug[:, :, d : d + dx, d + dx :] = np.eye(dx)
    e = expm_batch(aug)
    p_cut, g1, g2 = e[..., :d, :d], e[..., :d, d : d + dx], e[..., :d, d + dx :]
    w1, w0 = g2, g1 - g2  # the delayed position at the step's end / at its start
    free = {
        int(i): expm_batch(model.a0[None] * (period_s * widths[i])[:, None, None]) for i in range(m) if i not in cutting
    }
    # the initial delayed positions read during the period (the rest give zero columns)
    keep = sorted({k for i in cutting for k in (m - i, m - 1 - i) if 1 <= k <= m})
    n_keep = d + dx * len(keep)
    y = np.zeros((b, d, n_keep))
    y[:, :, :d] = np.eye(d)
    hist = [np.zeros((b, dx, n_keep)) for _ in range(m)]  # hist[k - 1]: x at grid point i - k
    for slot, k in enumerate(keep):
        hist[k - 1][:, :, d + dx * slot : d + dx * (slot + 1)] = np.eye(dx)
    where = {int(i): j for j, i in enumerate(cutting)}
    for i in range(m):
        if i in where:
            j = where[i]
            new_y = p_cut[:, j] @ y + w1[:, j] @ hist[m - 2] + w0[:, j] @ hist[m - 1]
        else:
            new_y = free[i] @ y
        hist.insert(0, model.c @ y)
        hist.pop()
        y = new_y
    mono = np.concatenate([y] + [hist[k - 1] for k in keep], axis=1)  # (b, n_keep, n_keep)
    mu = np.linalg.eigvals(mono)
    top = mu[np.arange(b), np.argmax(np.abs(mu), axis=1)]
    return np.abs(top), top


def sd_critical_depths(
    cut: Cut, dynamics: ToolDynamicsSpec, *, spindle_rpm, depth_max_m: float, n_depths: int = 100, steps: int = 20
) -> Lobes:
    """Critical depth (m) and chatter frequency (Hz) at each speed by semi-discretization.

    At each speed the tooth period in ``m`` steps in the cut: ``steps``, or more where a step
    would be longer than :data:`SD_STEPS_PER_CYCLE` of the highest mode's period (the delayed
    position is interpolated linearly between steps, so a step must be short against a
    vibration).  Speeds that would need over :data:`SD_MAX_STEPS` are not computed (nan).
    The spectral radius on ``n_depths`` depths up to ``depth_max_m``; the first unstable one
    refined by :data:`SD_BISECTIONS` bisections (nan: stable up to ``depth_max_m``); then the
    boundary with ``r = ``:data:`SD_FINER` times the steps near it (secant steps from it), and
    the two extrapolated to infinitely many steps (Richardson: the method's error falls as the
    step squared, so ``a = a_f + (a_f - a_m) / (r^2 - 1)``; where the finer boundary is not
    found within 20 % of the coarser one, the coarser one is kept).

    The chatter frequency is the critical multiplier's ``(arg mu + 2 pi k) / (2 pi T)`` (or
    its negative) nearest the most flexible mode's natural frequency.

    Raises
    ------
    TwinInputError
        A measured FRF (no modes), or a bad depth range or step count.
    """
    if not (np.isfinite(depth_max_m) and depth_max_m > 0):
        raise TwinInputError("depth_max_mm", depth_max_m * 1e3, "must be positive")
    if not 2 <= n_depths <= 10_000:
        raise TwinInputError("n_depths", n_depths, "2 to 10000")
    if not 4 <= steps <= SD_MAX_STEPS:
        raise TwinInputError("steps", steps, f"4 to {SD_MAX_STEPS} in the cut per tooth period")
    speeds = _speeds(spindle_rpm)
    model = ModalModel.of(dynamics)
    periods = cut.tooth_period_s(speeds)
    depths = np.linspace(depth_max_m / n_depths, depth_max_m, n_depths)
    highest_hz = max(m.frequency_hz for m in dynamics.modes)
    needed = np.maximum(steps, np.ceil(SD_STEPS_PER_CYCLE * highest_hz * periods)).astype(int)
    critical = np.full(len(speeds), np.nan)
    chatter = np.full(len(speeds), np.nan)
    for m in np.unique(needed[needed <= SD_MAX_STEPS]):
        group = np.flatnonzero(needed == m)
        critical[group], chatter[group] = _sd_boundary(model, cut, m=int(m), periods=periods[group], depths=depths)
    return Lobes("sd", speeds, critical, chatter)


def sd_slowest_rpm(cut: Cut, dynamics: ToolDynamicsSpec) -> float:
    """The lowest spindle speed (rpm) :func:`sd_critical_depths` computes for ``dynamics``."""
    highest_hz = max(m.frequency_hz for m in dynamics.modes)
    return 60.0 * SD_STEPS_PER_CYCLE * highest_hz / (cut.n_flutes * SD_MAX_STEPS)


def _sd_boundary(model: ModalModel, cut: Cut, *, m: int, periods: np.ndarray, depths: np.ndarray):
    """Critical depths (m) and chatter frequencies (Hz) at ``periods`` with ``m`` steps (see
    :func:`sd_critical_depths`)."""
    critical = np.full(len(periods), np.nan)
    chatter = np.full(len(periods), np.nan)
    m_fine = math.ceil(SD_FINER * m)
    coarse, fine = cut.step_matrices(m), cut.step_matrices(m_fine)
    first = _first_unstable(model, coarse, periods, depths)
    idx = np.flatnonzero(first >= 0)
    if idx.size == 0:
        return critical, chatter
    first = first[idx]
    lo = np.where(first > 0, depths[np.maximum(first - 1, 0)], 0.0)
    a_m, mu_m = _bisect(model, steps=coarse, periods=periods[idx], lo=lo, hi=depths[first])
    a_2m, mu_2m = _secant(model, fine, periods[idx], a_m)
    found = np.isfinite(a_2m)
    critical[idx] = np.where(found, a_2m + (a_2m - a_m) / ((m_fine / m) ** 2 - 1.0), a_m)
    mu = np.where(found, mu_2m, mu_m)
    chatter[idx] = _nearest_alias_hz(np.angle(mu), periods[idx], model.dominant_hz)
    return critical, chatter


def _secant(model: ModalModel, steps, periods: np.ndarray, start: np.ndarray):
    """Where the spectral radius crosses 1 near ``start`` (m) at each period, by
    :data:`SD_SECANTS` secant steps from ``start`` and 0.95 of it, and the multiplier there;
    nan where it does not settle within 20 % of ``start``."""
    x0, x1 = start, 0.95 * start
    f0 = sd_spectral_radius(model, steps, periods, x0)[0] - 1.0
    f1 = sd_spectral_radius(model, steps, periods, x1)[0] - 1.0
    mu = np.zeros(len(periods), complex)
    for _ in range(SD_SECANTS):
        with np.errstate(divide="ignore", invalid="ignore"):
            x2 = np.where(f1 != f0, x1 - f1 * (x1 - x0) / (f1 - f0), x1)
        x2 = np.clip(np.where(np.isfinite(x2), x2, start), 0.8 * start, 1.25 * start)
        radius, mu = sd_spectral_radius(model, steps, periods, x2)
        x0, f0, x1, f1 = x1, f1, x2, radius - 1.0
    settled = np.abs(f1) < SD_RADIUS_TOLERANCE
    return np.where(settled, x1, np.nan), mu


def _first_unstable(model: ModalModel, steps, periods: np.ndarray, depths: np.ndarray) -> np.ndarray:
    """Index of the first depth of ``depths`` (increasing) where the cut is unstable at each
    period (-1: none): the depths scanned upwards :data:`SD_SCAN` at a time, each speed until
    it has one (the same answer as the whole grid, at a fraction of its cost)."""
    first = np.full(len(periods), -1)
    open_ = np.arange(len(periods))
    for start in range(0, len(depths), SD_SCAN):
        block = depths[start : start + SD_SCAN]
        if open_.size == 0:
            break
        for s0 in range(0, open_.size, max(1, SD_BATCH // len(block))):
            rows = open_[s0 : s0 + max(1, SD_BATCH // len(block))]
            pp, dd = np.meshgrid(periods[rows], block, indexing="ij")
            rho = sd_spectral_radius(model, steps, pp.ravel(), dd.ravel())[0].reshape(len(rows), len(block))
            hit = (rho > 1.0).any(axis=1)
            first[rows[hit]] = start + np.argmax(rho[hit] > 1.0, axis=1)
        open_ = open_[first[open_] < 0]
    return first


def _bisect(model: ModalModel, *, steps, periods: np.ndarray, lo: np.ndarray, hi: np.ndarray):
    """The stability boundary between the depths ``lo`` (stable) and ``hi`` (unstable) at each
    period, by :data:`SD_BISECTIONS` bisections, and the critical multiplier at its upper end."""
    for _ in range(SD_BISECTIONS):
        mid = 0.5 * (lo + hi)
        unstable = sd_spectral_radius(model, steps, periods, mid)[0] > 1.0
        lo, hi = np.where(unstable, lo, mid), np.where(unstable, mid, hi)
    return 0.5 * (lo + hi), sd_spectral_radius(model, steps, periods, hi)[1]


def _nearest_alias_hz(angle_rad: np.ndarray, period_s: np.ndarray, near_hz: float) -> np.ndarray:
    """Of the frequencies ``(+-angle + 2 pi k) / (2 pi T)``, the one nearest ``near_hz``."""
    base = np.abs(angle_rad) / (2 * np.pi * period_s)
    tooth = 1.0 / period_s
    up = base + np.round((near_hz - base) / tooth) * tooth
    down = -base + np.round((near_hz + base) / tooth) * tooth
    return np.where(np.abs(up - near_hz) <= np.abs(down - near_hz), up, down)
