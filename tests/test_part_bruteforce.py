"""The virtual part's wall errors against an independent brute force written from geometry alone.

At a height z the actual part's material is the stock less every disc the tool sweeps between
consecutive samples (its radius at z over its tip: full above the corner, the corner's circle
within it, nothing at or under the tip). Here each wall point's signed distance to that cut is
the minimum over all segments of ``|p - q| - r`` (q the segment's nearest point to p, r the
tool's radius there), in numpy over every segment, no grid, no window: outside every capsule it
is the exact distance to the cut, inside it is the depth in the deepest capsule (the code's
documented overcut). A segment along which the tip moves (a plunge, a helix, a ramp) is cut in
pieces with the tip interpolated, each piece swept at the larger and at the smaller of its ends'
radii: the continuous sweep lies between the two, and their spread is the bound stated where it
matters. A second reference reads the furthest reach of the discs along a ray (bores and slot
widths), and a least-squares circle through brute-force boundary points checks the inspection.
"""

import math
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest
import shapely

from twin.machining.inspection import CircleFeature, WidthFeature, measure
from twin.machining.part import machined_part
from twin.machining.sweep import ToolSweep
from twin.records import CircleMeasured, WidthMeasured

UM = 1e-3  # mm
TOL_UM = 0.01  # the wall error's agreement (µm)
CLIP_UM = 1000.0  # the code's window: errors clipped there


# --- the reference ------------------------------------------------------------------------


def tool_radius(tip, radius, corner, z):
    """The tool's radius at height z over its tip (mm), written from the tool's profile."""
    h = z - np.asarray(tip, float)
    radius = np.broadcast_to(np.asarray(radius, float), h.shape)
    corner = np.broadcast_to(np.asarray(corner, float), h.shape)
    inside = np.clip(h, 0.0, None)
    within = radius - corner + np.sqrt(np.clip(corner**2 - (corner - inside) ** 2, 0.0, None))
    return np.where(h <= 0.0, 0.0, np.where(h >= corner, radius, within))


def capsules(sweep: ToolSweep, z: float, pieces: int = 64):
    """The segments the tool sweeps at height z: starts (k, 2), ends (k, 2), radius lower and
    upper bounds (k,), the line of the segment's first sample, or -1 where its two samples'
    lines differ (k,). A segment whose tip changes is cut into ``pieces`` with the tip
    interpolated; a lone sample is a segment of length 0."""
    xy, tip = np.asarray(sweep.xy_mm, float), np.asarray(sweep.tip_mm, float)
    rad, cor, line = np.asarray(sweep.radius_mm, float), np.asarray(sweep.corner_mm, float), sweep.line
    if len(xy) == 1:
        r = tool_radius(tip, rad, cor, z)
        return xy, xy, r, r, np.asarray(line)
    line = np.where(line[:-1] == line[1:], line[:-1], -1)
    a, b = xy[:-1], xy[1:]
    ta, tb = tip[:-1], tip[1:]
    ra, rb = tool_radius(ta, rad[:-1], cor[:-1], z), tool_radius(tb, rad[1:], cor[1:], z)
    steady = (ta == tb) | (ra == rb)
    starts, ends, lo, hi, lines = [a[steady]], [b[steady]], [ra[steady]], [ra[steady]], [line[steady]]
    moving = np.flatnonzero(~steady & ((ra > 0) | (rb > 0)))
    if len(moving):
        t = np.linspace(0.0, 1.0, pieces + 1)
        pa, pb = a[moving], b[moving]
        p = pa[:, None, :] + (pb - pa)[:, None, :] * t[None, :, None]  # (j, pieces + 1, 2)
        tips = ta[moving, None] + (tb - ta)[moving, None] * t[None, :]
        r_ = tool_radius(tips, rad[moving, None], cor[moving, None], z)
        starts.append(p[:, :-1].reshape(-1, 2))
        ends.append(p[:, 1:].reshape(-1, 2))
        lo.append(np.minimum(r_[:, :-1], r_[:, 1:]).ravel())
        hi.append(np.maximum(r_[:, :-1], r_[:, 1:]).ravel())
        lines.append(np.repeat(line[moving], pieces))
    keep = np.concatenate(hi) > 0.0
    cat = [np.concatenate(v)[keep] for v in (starts, ends, lo, hi, lines)]
    return tuple(cat)


def segment_distance(p: np.ndarray, a: np.ndarray, b: np.ndarray):
    """|p - q| for q the nearest point of each segment a-b to each point p: (m, k), and q."""
    d = b - a
    len2 = np.einsum("ij,ij->i", d, d)
    ap = p[:, None, :] - a[None, :, :]
    with np.errstate(invalid="ignore", divide="ignore"):
        t = np.where(len2 > 0, np.einsum("mki,ki->mk", ap, d) / len2, 0.0)
    t = np.clip(t, 0.0, 1.0)
    q = a[None] + t[..., None] * d[None]
    return np.hypot(p[:, None, 0] - q[..., 0], p[:, None, 1] - q[..., 1]), q


def brute_walls(points: np.ndarray, sweep: ToolSweep, pieces: int = 64, budget: int = 2_000_000):
    """For wall points (m, 3): the signed distance (µm) to the actual cut at each point's z,
    bracketed: with each piece at its larger radius (the smaller distance) and at its smaller
    (m,) each; the line credited, and the margin (µm) to the nearest segment of another line."""
    m = len(points)
    near, far = np.full(m, np.inf), np.full(m, np.inf)
    line, other = np.full(m, -1), np.full(m, np.inf)
    for z in np.unique(points[:, 2]):
        at = np.flatnonzero(points[:, 2] == z)
        a, b, r_lo, r_hi, lines = capsules(sweep, float(z), pieces)
        step = max(1, budget // max(len(a), 1))
        for i in range(0, len(at), step):
            rows = at[i : i + step]
            dist, _ = segment_distance(points[rows, :2], a, b)
            d_near, d_far = dist - r_hi, dist - r_lo
            best = np.argmin(d_near, axis=1)
            near[rows] = d_near[np.arange(len(rows)), best]
            far[rows] = d_far.min(axis=1)
            line[rows] = lines[best]
            other[rows] = np.where(lines[None, :] != line[rows, None], d_near, np.inf).min(axis=1)
    return near / UM, far / UM, line, (other - near) / UM


def densified(xy: np.ndarray, times: int) -> np.ndarray:
    """The polyline ``xy`` with ``times - 1`` points interpolated in each segment."""
    t = np.arange(times) / times
    inner = xy[:-1, None, :] + (xy[1:] - xy[:-1])[:, None, :] * t[None, :, None]
    return np.vstack([inner.reshape(-1, 2), xy[-1:]])


def ray_reach(centre, angles: np.ndarray, xy: np.ndarray, radius: float) -> np.ndarray:
    """The furthest the discs of ``radius`` at ``xy`` reach along rays from ``centre`` at
    ``angles``: over the discs whose polar angle is within reach of each ray (all of them that
    hold the centre or come near it)."""
    rel = xy - centre
    rho, phi = np.hypot(rel[:, 0], rel[:, 1]), np.arctan2(rel[:, 1], rel[:, 0])
    wide = rho <= 2 * radius  # near the centre: offered to every ray
    half = float(np.arcsin(radius / rho[~wide].min())) + 1e-9 if (~wide).any() else 0.0
    order = np.argsort(phi[~wide])
    phi_s, rho_s = phi[~wide][order], rho[~wide][order]
    phi_s, rho_s = np.concatenate([phi_s - 2 * np.pi, phi_s, phi_s + 2 * np.pi]), np.tile(rho_s, 3)
    out = np.empty(len(angles))
    for i, theta in enumerate(angles):
        lo, hi = np.searchsorted(phi_s, [theta - half, theta + half])
        p = np.concatenate([phi_s[lo:hi], phi[wide]])
        r = np.concatenate([rho_s[lo:hi], rho[wide]])
        along, across = r * np.cos(p - theta), r * np.sin(p - theta)
        reach = np.where(np.abs(across) < radius, along + np.sqrt(np.maximum(radius**2 - across**2, 0.0)), -np.inf)
        out[i] = reach.max()
    return out


def sweep(xy, tip, radius, corner=0.0, line=1) -> ToolSweep:
    xy = np.asarray(xy, float)
    n = len(xy)

    def full(v):
        return np.broadcast_to(np.asarray(v, float), (n,)).copy()

    return ToolSweep(xy, full(tip), full(radius), full(corner), np.broadcast_to(np.asarray(line), (n,)).astype(int))


def check(part, pieces: int = 64, tol_um: float = TOL_UM, min_points: int = 50):
    """Every wall point read within the window against the brute force (within ``tol_um`` of
    the bracket of the continuous sweep) and the lines credited: the walls."""
    walls = part.walls
    near, far, line, gap = brute_walls(walls[:, :3], part.actual, pieces)
    read = np.abs(walls[:, 3]) < CLIP_UM
    assert read.sum() >= min_points
    # beyond the window the code reads its clip: so must the brute force (at least that far)
    assert np.all(near[~read] >= CLIP_UM - tol_um)
    got = walls[read, 3]
    # the continuous sweep lies between the two radius bounds (equal for a steady tip)
    err = np.maximum(np.maximum(near[read] - got, got - far[read]), 0.0)
    worst = float(err.max())
    assert worst <= tol_um, f"largest difference {worst:.4g} µm at {walls[read][np.argmax(err), :4]}"
    # the line credited (the nearest capsule's first sample's), where one line's capsule is
    # unambiguously the nearest
    sure = read & (gap > 1e-3) & (line >= 0)
    np.testing.assert_array_equal(walls[sure, 4], line[sure])
    return walls


# --- 1. a through-cut -----------------------------------------------------------------------


def test_through_cut_slot_with_noise_and_an_offset_half():
    stock = shapely.box(0.0, 0.0, 40.0, 20.0)
    n = 6001
    x = np.linspace(5.0, 35.0, n)
    nominal = sweep(np.column_stack([x, np.full(n, 10.0)]), -12.0, 3.0, line=4)
    rng = np.random.default_rng(1)
    actual_xy = nominal.xy_mm + rng.normal(0.0, 1.0 * UM, (n, 2))
    actual_xy[x > 20.0, 1] += 5.0 * UM
    actual = sweep(actual_xy, -12.0, 3.0, line=4)
    part = machined_part(stock, nominal, actual, top_mm=0.0, bottom_mm=-10.0)
    assert len(part.levels_mm) >= 1
    assert all(-10.0 < z < 0.0 for z in part.levels_mm)
    walls = check(part, min_points=1000)
    # the offset half: its upper wall overcut some 5 µm, its lower wall left material
    upper = (walls[:, 0] > 22) & (walls[:, 0] < 34) & (walls[:, 1] > 12.9)
    lower = (walls[:, 0] > 22) & (walls[:, 0] < 34) & (walls[:, 1] < 7.1)
    assert -9.0 < np.median(walls[upper, 3]) < -4.0
    assert 2.0 < np.median(walls[lower, 3]) < 6.0


# --- 2. a helix -----------------------------------------------------------------------------


def helix(radius_mm: float, n_turns: float = 3.5, per_turn: int = 4000):
    """A helical entry at radius ``radius_mm`` about (20, 10) from Z 0.5 to -3 (pitch 1 mm),
    then a full circle at Z -3: xy, tips."""
    turns = np.linspace(0.0, n_turns, int(n_turns * per_turn) + 1)
    last = np.linspace(n_turns, n_turns + 1.0, per_turn + 1)[1:]
    angle = 2 * np.pi * np.concatenate([turns, last])
    tip = np.concatenate([0.5 - turns, np.full(len(last), 0.5 - n_turns)])
    xy = np.column_stack([20.0 + radius_mm * np.cos(angle), 10.0 + radius_mm * np.sin(angle)])
    return xy, tip


def test_helical_bore_entry_with_a_radial_error():
    stock = shapely.box(0.0, 0.0, 40.0, 20.0)
    xy, tip = helix(3.0, per_turn=1000)
    nominal = sweep(xy, tip, 3.0, line=9)
    xy_a, tip_a = helix(3.0 + 2.0 * UM, per_turn=1000)
    actual = sweep(xy_a, tip_a, 3.0, line=9)
    part = machined_part(stock, nominal, actual, top_mm=0.0, bottom_mm=-10.0)
    assert part.levels_mm  # the level(s) it reads, between the top and the -3 floor
    walls = check(part, min_points=300)
    # closed form: a circle of radius 3 + 3 µm cut by the 6 mm tool: the wall 2 µm overcut
    bore = np.hypot(walls[:, 0] - 20.0, walls[:, 1] - 10.0) > 5.9
    np.testing.assert_allclose(walls[bore, 3], -2.0, atol=TOL_UM)
    # and the ray reach of the actual discs cut below each level, at 1440 angles
    for z in part.levels_mm:
        cut = tip_a < z
        at = bore & (walls[:, 2] == z)
        angles = np.arctan2(walls[at, 1] - 10.0, walls[at, 0] - 20.0)
        reach = ray_reach((20.0, 10.0), angles, densified(xy_a[cut], 4), 3.0)
        radius = np.hypot(walls[at, 0] - 20.0, walls[at, 1] - 10.0)
        np.testing.assert_allclose(walls[at, 3], (radius - reach) / UM, atol=TOL_UM)


# --- 3. a plunge then a side move, ball and bull-nose tools --------------------------------


def plunge_and_pass(corner: float, noise_um: float):
    """A plunge at (10, 10) from Z 1 to -2, a pass to X 30 (line 4), a retract, a shallower
    pass back at Y 14 (tip -0.6, line 5); the actual path ``noise_um`` of noise, 3 µm towards
    +Y and its tip 2 µm lower (a wider cut by the radius at each height): the stock, both."""
    plunge = np.linspace(1.0, -2.0, 31)
    x = np.linspace(10.0, 30.0, 2001)
    x2 = np.linspace(30.0, 10.0, 2001)
    xy = np.vstack(
        [
            np.tile([[10.0, 10.0]], (len(plunge), 1)),
            np.column_stack([x, np.full(len(x), 10.0)]),
            [[30.0, 10.0], [30.0, 14.0]],
            np.column_stack([x2, np.full(len(x2), 14.0)]),
        ]
    )
    tip = np.concatenate([plunge, np.full(len(x), -2.0), [5.0, 5.0], np.full(len(x2), -0.6)])
    line = np.concatenate([np.full(len(plunge), 3), np.full(len(x), 4), [5, 5], np.full(len(x2), 5)])
    nominal = ToolSweep(xy, tip, np.full(len(xy), 3.0), np.full(len(xy), corner), line)
    xy_a = xy + np.random.default_rng(3).normal(0.0, noise_um * UM, xy.shape) + [0.0, 3.0 * UM]
    # the retract and the plunge straight up and down (a segment whose tip moves while it
    # moves in XY is swept otherwise: test_a_segment_along_which_the_tip_moves)
    up = len(plunge) + len(x)
    xy_a[up] = xy_a[up - 1]
    xy_a[up + 1] = xy_a[up + 2]
    actual = ToolSweep(xy_a, tip - 2.0 * UM, nominal.radius_mm, nominal.corner_mm, line)
    return shapely.box(0.0, 0.0, 40.0, 20.0), nominal, actual


@pytest.mark.parametrize("corner", [1.0, 3.0], ids=["bull_nose", "ball"])
def test_plunge_then_side_move_radius_by_height(corner):
    stock, nominal, actual = plunge_and_pass(corner, 0.5)
    part = machined_part(stock, nominal, actual, top_mm=0.0, bottom_mm=-10.0)
    assert part.levels_mm == [-0.3, -1.3]  # the floors -0.6 and -2
    check(part, min_points=500)
    # without the noise, a closed form on the deep pass's straight lower wall (the nominal
    # radius r at z, the actual r_a of a tip 2 µm lower, the path 3 µm towards +Y): material
    # left 3 µm - (r_a - r); at -0.3 the bull-nose is within its corner (h 0.3 of 1)
    part = machined_part(*plunge_and_pass(corner, 0.0), top_mm=0.0, bottom_mm=-10.0)
    walls = part.walls
    for z in part.levels_mm:
        r, r_a = tool_radius(-2.0, 3.0, corner, z), tool_radius(-2.0 - 2 * UM, 3.0, corner, z)
        low = (walls[:, 2] == z) & (walls[:, 0] > 13) & (walls[:, 0] < 27) & (walls[:, 1] < 10.0)
        assert low.sum() > 200
        np.testing.assert_allclose(walls[low, 3], (3 * UM - (r_a - r)) / UM, atol=TOL_UM)
    shallow = tool_radius(-0.6, 3.0, corner, -0.3)
    up = (walls[:, 2] == -0.3) & (walls[:, 0] > 13) & (walls[:, 0] < 27) & (walls[:, 1] > 14.0)
    assert np.all(np.abs(walls[up, 1] - 14.0 - shallow) < 1e-4)  # the nominal wall at r(z)
    r_a = tool_radius(-0.6 - 2 * UM, 3.0, corner, -0.3)
    np.testing.assert_allclose(walls[up, 3], (-3 * UM - (r_a - shallow)) / UM, atol=TOL_UM)


def ramp(coarse: bool):
    """A ball tool (6 mm) ramping from tip -0.2 to -1.2 over X 5 to 25, then level to X 35:
    200 samples on the ramp (the tip 5 µm down per sample), or 2."""
    k = 2 if coarse else 201
    x = np.concatenate([np.linspace(5.0, 25.0, k), np.linspace(25.0, 35.0, 101)[1:]])
    tip = np.concatenate([np.linspace(-0.2, -1.2, k), np.full(100, -1.2)])
    return np.column_stack([x, np.full(len(x), 10.0)]), tip


@pytest.mark.parametrize(
    ("coarse", "tol_um"),
    # 2 samples: one 20 mm segment whose radius at the level grows as a square root from the
    # ball's tip: the code's 64 pieces (spaced as squares from the crossing), each the hull of
    # its end discs, lie inside the continuous sweep by up to 0.5 µm there
    [(False, TOL_UM), (True, 0.5)],
    ids=["ramp_200_samples", "ramp_2_samples"],
)
def test_a_segment_along_which_the_tip_moves(coarse, tol_um):
    # between two samples the tip moves: the discs' radius at the level changes along the
    # segment; the continuous sweep is bracketed by the pieces' radius bounds (64 pieces)
    stock = shapely.box(0.0, 0.0, 40.0, 20.0)
    xy, tip = ramp(coarse)
    nominal = sweep(xy, tip, 3.0, corner=3.0, line=2)
    actual = sweep(xy + np.array([0.0, 1.0 * UM]), tip, 3.0, corner=3.0, line=2)
    part = machined_part(stock, nominal, actual, top_mm=0.0, bottom_mm=-10.0)
    check(part, pieces=64, tol_um=tol_um, min_points=100)


def test_a_ball_finishing_pass_over_a_surface_sampled_coarsely():
    # a 6 mm ball over a sine surface, its tip changing at every sample and the samples 50 µm
    # apart (3000 mm/min at 1 ms): at a level through the valleys the swept radius changes fast
    # from sample to sample; the walls there against the brute force's bracket
    stock = shapely.box(0.0, 0.0, 40.0, 20.0)
    x = np.arange(2.0, 38.0, 0.05)
    rows = []
    for k, y in enumerate((8.0, 12.0)):
        rows.append(np.column_stack([x if k == 0 else x[::-1], np.full(len(x), y)]))
    xy = np.concatenate([*rows, np.column_stack([np.linspace(12.0, 14.0, 40), np.full(40, 16.0)])])
    tip = np.concatenate([-1.0 - 0.8 * np.sin(xy[:-40, 0] / 3.0), np.full(40, -1.9)])  # -1.8 to -0.2
    nominal = sweep(xy, tip, 3.0, corner=3.0, line=5)
    actual = sweep(xy + np.array([0.0, 2.0 * UM]), tip, 3.0, corner=3.0, line=5)
    part = machined_part(stock, nominal, actual, top_mm=0.0, bottom_mm=-10.0)
    assert part.levels_mm == [-0.95]  # the level pass's floor -1.9: the rows' valleys cross it
    walls = check(part, pieces=64, tol_um=0.05, min_points=200)
    # the path 2 µm towards +Y: the outer walls move by at most that much
    assert np.abs(walls[:, 3]).max() < 2.0 + 0.05


# --- 4. many passes, an island --------------------------------------------------------------


def test_five_passes_the_deepest_forms_the_wall_and_a_stock_with_a_hole():
    hole = shapely.Point(20.0, 10.0).buffer(2.0, quad_segs=64)
    stock = shapely.box(0.0, 0.0, 40.0, 20.0).difference(hole)
    n = 1501
    x = np.linspace(5.0, 35.0, n)
    offsets = [0.0, 2.0, -3.0, 1.0, 4.0]  # µm in Y
    rng = np.random.default_rng(4)
    nom, act, tips, lines = [], [], [], []
    for k, off in enumerate(offsets):
        xs = x if k % 2 == 0 else x[::-1]
        path = np.column_stack([xs, np.full(n, 10.0)])
        # a plunge and a retract at the pass's ends, at the same XY
        nom += [path[:1], path, path[-1:]]
        shifted = path + np.array([0.0, off * UM]) + rng.normal(0.0, 0.2 * UM, path.shape)
        act += [shifted[:1], shifted, shifted[-1:]]
        tips += [[5.0], np.full(n, -2.0), [5.0]]
        lines += [np.full(n + 2, 10 + k)]
    xy, xy_a, tip, line = np.vstack(nom), np.vstack(act), np.concatenate(tips), np.concatenate(lines)
    nominal = ToolSweep(xy, tip, np.full(len(xy), 3.0), np.zeros(len(xy)), line)
    actual = ToolSweep(xy_a, tip, np.full(len(xy), 3.0), np.zeros(len(xy)), line)
    part = machined_part(stock, nominal, actual, top_mm=0.0, bottom_mm=-10.0)
    walls = check(part, min_points=500)
    # no wall on the hole's own outline
    assert np.all(shapely.distance(shapely.points(walls[:, :2]), hole.exterior) > 1e-4)
    straight = (walls[:, 0] > 9) & (walls[:, 0] < 31)
    upper, lower = straight & (walls[:, 1] > 10), straight & (walls[:, 1] < 10)
    # the wall is the deepest pass's: +4 µm up (line 14), -3 µm down (line 12)
    assert np.median(walls[upper, 3]) == pytest.approx(-4.0, abs=0.5)
    assert np.median(walls[lower, 3]) == pytest.approx(-3.0, abs=0.5)
    assert np.mean(walls[upper, 4] == 14) > 0.9
    assert np.mean(walls[lower, 4] == 12) > 0.9


# --- 5. tools of any diameter ---------------------------------------------------------------


def test_a_100_mm_face_mill():
    stock = shapely.box(0.0, 0.0, 80.0, 40.0)
    n = 4001
    x = np.linspace(40.0, 140.0, n)  # starts in the stock: its 50 mm radius forms an arc wall
    nominal = sweep(np.column_stack([x, np.full(n, -20.0)]), -1.0, 50.0, line=6)
    rng = np.random.default_rng(5)
    actual = sweep(nominal.xy_mm + rng.normal(0.0, 1.0 * UM, (n, 2)) + [-2 * UM, 3 * UM], -1.0, 50.0, line=6)
    part = machined_part(stock, nominal, actual, top_mm=0.0, bottom_mm=-10.0)
    walls = check(part, min_points=1000)
    arc = walls[:, 0] < 39.0
    assert arc.sum() > 100  # the disc's own arc at the start


def test_a_half_millimetre_tool_round_a_corner():
    stock = shapely.box(0.0, 0.0, 10.0, 5.0)
    leg1 = np.column_stack([np.linspace(1.0, 8.0, 1401), np.full(1401, 1.5)])
    leg2 = np.column_stack([np.full(601, 8.0), np.linspace(1.5, 4.5, 601)])[1:]
    xy = np.vstack([leg1, leg2])
    line = np.concatenate([np.full(1401, 1), np.full(600, 2)])
    nominal = ToolSweep(xy, np.full(len(xy), -0.5), np.full(len(xy), 0.25), np.zeros(len(xy)), line)
    rng = np.random.default_rng(6)
    actual = ToolSweep(
        xy + rng.normal(0.0, 1.0 * UM, xy.shape), nominal.tip_mm, nominal.radius_mm, nominal.corner_mm, line
    )
    part = machined_part(stock, nominal, actual, top_mm=0.0, bottom_mm=-10.0)
    check(part, min_points=300)


# --- 6. inspection --------------------------------------------------------------------------


def fit_circle_ls(points: np.ndarray):
    """Least-squares circle (geometric, Gauss-Newton from the algebraic fit): centre, radius."""
    x, y = points[:, 0], points[:, 1]
    a = np.column_stack([x, y, np.ones(len(x))])
    c = np.linalg.lstsq(a, x**2 + y**2, rcond=None)[0]
    centre = np.array([c[0] / 2, c[1] / 2])
    radius = math.sqrt(c[2] + centre @ centre)
    for _ in range(20):
        rel = points - centre
        rho = np.hypot(rel[:, 0], rel[:, 1])
        jac = np.column_stack([-rel[:, 0] / rho, -rel[:, 1] / rho, -np.ones(len(rho))])
        delta = np.linalg.lstsq(jac, -(rho - radius), rcond=None)[0]
        centre, radius = centre + delta[:2], radius + delta[2]
    return centre, radius


def test_bore_diameter_and_slot_width_against_the_brute_force():
    stock = shapely.box(-40.0, -40.0, 40.0, 40.0)
    turn = np.linspace(0.0, 2 * np.pi, 20_001)
    n = len(turn)
    nominal = sweep(np.column_stack([28 * np.cos(turn), 28 * np.sin(turn)]), -3.0, 5.0, line=12)
    rng = np.random.default_rng(7)
    rad = 28.0 + (3.0 + 2.0 * np.cos(2 * turn) + rng.normal(0.0, 1.0, n)) * UM
    xy_a = np.column_stack([rad * np.cos(turn), rad * np.sin(turn)])
    actual = sweep(xy_a, -3.0, 5.0, line=12)
    part = machined_part(stock, nominal, actual, top_mm=0.0, bottom_mm=-10.0)
    row = measure(CircleFeature(type="circle", name="bore", center_mm=(0, 0), diameter_mm=66.0, z_mm=-1.5), part)
    # ray reach at 1440 angles (the actual samples densified 4x: the capsules' sides)
    theta = np.linspace(-np.pi, np.pi, 1440, endpoint=False)
    reach = ray_reach((0.0, 0.0), theta, densified(xy_a, 4), 5.0)
    assert isinstance(row, CircleMeasured)
    assert row.diameter_mm == pytest.approx(2 * reach.mean(), abs=1e-4)  # 0.1 µm: a mean, not a fit (0.013 µm)
    # the least-squares circle through the brute-force boundary points nearest probes every
    # 0.02 mm on the nominal circle (the nearest capsule's side on the ray from its axis)
    phi = np.linspace(0.0, 2 * np.pi, int(2 * np.pi * 33 / 0.02), endpoint=False)
    probes = 33.0 * np.column_stack([np.cos(phi), np.sin(phi)])
    # (each probe against the 401 segments nearest its angle: ±0.063 rad, 1.8 mm of the path;
    # the nearest is on its ray, within a few µm)
    near = (np.rint(phi / (2 * np.pi) * (n - 1)).astype(int)[:, None] + np.arange(-200, 201)) % (n - 1)
    surface = np.empty_like(probes)
    for i in range(0, len(probes), 1000):
        p, k = probes[i : i + 1000], near[i : i + 1000]
        a, d = xy_a[k], xy_a[k + 1] - xy_a[k]  # (1000, 401, 2)
        t = np.clip(np.einsum("mki,mki->mk", p[:, None] - a, d) / np.einsum("mki,mki->mk", d, d), 0.0, 1.0)
        q = a + t[..., None] * d
        qb = q[np.arange(len(p)), np.argmin(np.hypot(p[:, None, 0] - q[..., 0], p[:, None, 1] - q[..., 1]), axis=1)]
        away = p - qb
        surface[i : i + 1000] = qb + away * (5.0 / np.hypot(away[:, 0], away[:, 1]))[:, None]
    centre, radius = fit_circle_ls(surface)
    assert row.diameter_mm == pytest.approx(2 * radius, abs=1e-5)  # 0.01 µm (the fit: 0.0003 µm)
    assert np.hypot(*centre) < 2e-3

    # a slot's width across the line X 15 against the exact extent of the capsules along it
    slot_stock = shapely.box(0.0, 0.0, 30.0, 20.0)
    x = np.linspace(5.0, 25.0, 2001)
    nom = sweep(np.column_stack([x, np.full(len(x), 10.0)]), -2.0, 3.0, line=7)
    act_xy = nom.xy_mm + rng.normal(0.0, 1.0 * UM, nom.xy_mm.shape) + [0.0, 2.0 * UM]
    slot = machined_part(slot_stock, nom, sweep(act_xy, -2.0, 3.0, line=7), top_mm=0.0, bottom_mm=-10.0)
    width = measure(
        WidthFeature(type="width", name="w", from_mm=(15, 5), to_mm=(15, 15), width_mm=6.0, z_mm=-1.0), slot
    )
    lo, hi = line_gap(act_xy, 3.0, np.array([15.0, 5.0]), np.array([15.0, 15.0]))
    assert isinstance(width, WidthMeasured)
    assert width.width_mm == pytest.approx(hi - lo, abs=1e-5)
    assert width.deviation_um == pytest.approx((hi - lo - 6.0) / UM, abs=0.1)


def line_gap(xy: np.ndarray, radius: float, start: np.ndarray, end: np.ndarray):
    """The open gap the capsules of ``radius`` along ``xy`` cut on the line from ``start`` to
    ``end``, the one holding its middle: (s_lo, s_hi) in mm along the line, exact (each capsule
    meets the line in an interval: the hull of its two end discs' and its band's)."""
    u = (end - start) / np.linalg.norm(end - start)
    a, b = xy[:-1], xy[1:]
    intervals = []
    for c in (a, b):  # the end discs
        rel = c - start
        along, across = rel @ u, rel @ np.array([-u[1], u[0]])
        half = np.sqrt(np.maximum(radius**2 - across**2, 0.0))
        ok = np.abs(across) <= radius
        intervals.append(np.where(ok, along - half, np.inf))
        intervals.append(np.where(ok, along + half, -np.inf))
    lo = np.minimum(intervals[0], intervals[2])
    hi = np.maximum(intervals[1], intervals[3])
    # the band: |cross(L(s) - a, d)| <= r |d| and 0 <= (L(s) - a).d <= |d|^2, linear in s
    d = b - a
    dn = np.hypot(d[:, 0], d[:, 1])
    ok = dn > 0
    rel = start - a
    c0, c1 = rel[:, 0] * d[:, 1] - rel[:, 1] * d[:, 0], u[0] * d[:, 1] - u[1] * d[:, 0]
    p0, p1 = np.einsum("ij,ij->i", rel, d), d @ u
    s_lo, s_hi = np.full(len(a), -np.inf), np.full(len(a), np.inf)
    for k0, k1, low, high in ((c0, c1, -radius * dn, radius * dn), (p0, p1, 0.0 * dn, dn**2)):
        with np.errstate(divide="ignore", invalid="ignore"):
            e1, e2 = (low - k0) / k1, (high - k0) / k1
        flat = k1 == 0
        inside = (k0 >= low) & (k0 <= high)
        s_lo = np.maximum(s_lo, np.where(flat, np.where(inside, -np.inf, np.inf), np.minimum(e1, e2)))
        s_hi = np.minimum(s_hi, np.where(flat, np.where(inside, np.inf, -np.inf), np.maximum(e1, e2)))
    band = ok & (s_lo <= s_hi)
    lo = np.where(band, np.minimum(lo, s_lo), lo)
    hi = np.where(band, np.maximum(hi, s_hi), hi)
    keep = lo <= hi
    order = np.argsort(lo[keep])
    lo, hi = lo[keep][order], hi[keep][order]
    middle = 0.5 * np.linalg.norm(end - start)
    run_lo, run_hi = lo[0], hi[0]
    for s0, s1 in zip(lo[1:], hi[1:], strict=True):
        if s0 > run_hi:
            if run_lo <= middle <= run_hi:
                break
            run_lo, run_hi = s0, s1
        else:
            run_hi = max(run_hi, s1)
    assert run_lo <= middle <= run_hi
    return run_lo, run_hi


# --- 7. memory and time ---------------------------------------------------------------------


def long_jitter_case(n: int = 2_000_000):
    """A slot 100 mm along X at Y 25 through a 100 x 50 mm stock, 6 mm tool 2 mm deep: the
    nominal path smooth, the actual one ``n`` samples (0.05 µm apart) with 1 µm noise."""
    stock = shapely.box(0.0, 0.0, 100.0, 50.0)
    x = np.linspace(0.0, 100.0, 2001)
    nominal = sweep(np.column_stack([x, np.full(len(x), 25.0)]), -2.0, 3.0, line=3)
    rng = np.random.default_rng(8)
    xa = np.linspace(0.0, 100.0, n)
    xy = np.column_stack([xa, np.full(n, 25.0)]) + rng.normal(0.0, 1.0 * UM, (n, 2))
    return stock, nominal, sweep(xy, -2.0, 3.0, line=3)


@pytest.mark.slow
@pytest.mark.skipif(not Path("/proc/self/status").exists(), reason="peak RSS read from /proc (Linux)")
def test_two_million_jittery_samples_in_bounded_memory(tmp_path):
    script = textwrap.dedent(
        f"""
        import sys, time
        import numpy as np
        sys.path.insert(0, {str(Path(__file__).parent)!r})
        import test_part_bruteforce as t
        case = t.long_jitter_case()
        t.machined_part(*t.long_jitter_case(2000), top_mm=0.0, bottom_mm=-10.0)  # compiled before the clock starts
        def peak_mb():  # this process's peak RSS (ru_maxrss would carry pytest's over exec)
            status = open("/proc/self/status").read().split("VmHWM:")[1]
            return int(status.split()[0]) / 1024
        before = peak_mb()
        start = time.perf_counter()
        part = t.machined_part(*case, top_mm=0.0, bottom_mm=-10.0)
        seconds = time.perf_counter() - start
        np.save({str(tmp_path / "walls.npy")!r}, part.walls)
        print(before, peak_mb(), seconds)
        """
    )
    out = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, check=True, timeout=300)
    before_mb, peak_mb, seconds = map(float, out.stdout.split())
    print(f"peak RSS {before_mb:.0f} MB before, {peak_mb:.0f} MB after; {seconds:.1f} s")
    assert peak_mb < 1024.0, out.stdout
    assert peak_mb - before_mb < 256.0, out.stdout  # the part's own (the path's arrays before)
    assert seconds < 60.0
    walls = np.load(tmp_path / "walls.npy")
    assert len(walls) > 3000
    # the brute force on 200 wall points, each against the segments within reach of it
    _, _, actual = long_jitter_case()
    pick = np.random.default_rng(9).choice(len(walls), 200, replace=False)
    n = len(actual.xy_mm)
    for i in pick:
        p = walls[i]  # the samples are 0.05 µm apart along X, 1 µm of noise: those within 4.1 mm
        lo, hi = (np.array([p[0] - 4.1, p[0] + 4.1]) / 100.0 * (n - 1)).astype(int)
        lo, hi = max(lo, 0), min(hi, n)
        a, b = actual.xy_mm[lo : hi - 1], actual.xy_mm[lo + 1 : hi]
        dist, _ = segment_distance(p[None, :2], a, b)
        ref = (dist.min() - 3.0) / UM
        if abs(p[3]) < CLIP_UM:
            assert p[3] == pytest.approx(ref, abs=TOL_UM)
