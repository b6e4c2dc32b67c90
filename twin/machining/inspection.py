"""Inspection of the virtual part as a coordinate measuring machine reports it.

Each ``[[inspect]]`` feature names a place on the nominal part; it is measured on the actual
part at its ``z_mm`` by probes every :data:`PROBE_STEP_MM` along the nominal feature
(:meth:`twin.machining.part.MachinedPart.probe`): each finds the nearest point of the actual cut's
boundary (the side of the nearest capsule the tool swept), and those within :data:`BAND_MM` of
the nominal feature are its measured points:

- ``circle`` (a bore or a boss): the least-squares circle (geometric, scipy's
  ``least_squares`` from the algebraic fit); its diameter, centre and roundness (the spread of
  the radial residuals, peak to valley);
- ``line`` (a wall from ``from_mm`` to ``to_mm``): the least-squares line (total, through the
  points' principal axis); its position where the nominal line's middle falls on it, the signed
  offset from the nominal (positive: material left) and straightness (peak to valley);
- ``width`` (a slot or pocket): the two-point size along the line ``from_mm`` to ``to_mm``
  across it: the length of the open gap that holds the line's middle, each end where the line
  meets the side of the capsule nearest the first probe in material (or the stock's outline).

``deviation_um`` is the measured less the nominal; ``pass`` holds it within ``tolerance_um``.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, Any, Literal

import numpy as np
import shapely
from pydantic import Field, PositiveFloat
from scipy.optimize import least_squares

from controllers.registries import Registry
from twin.machining.engagement import StockSpec
from twin.machining.part import MachinedPart
from twin.records import CircleMeasured, FeatureNotFound, FeatureType, Inspected, LineMeasured, WidthMeasured
from twin.spec import MAX_MM, Millimetres, ReportName, StrictSpec, register_kind, tagged_union

#: Distance from a nominal feature (mm) within which the boundary counts as its points.
BAND_MM = 0.5
#: Spacing of the probed points along the boundary (mm).
PROBE_STEP_MM = 0.02
#: Points a feature needs to be measured.
MIN_POINTS = 8
#: A point [x, y] of a feature (mm).
Point = tuple[Millimetres, Millimetres]


class _Feature(StrictSpec):
    name: ReportName = Field(description="the feature's name in the report")
    z_mm: Millimetres = Field(description="height measured at (mm)")
    tolerance_um: PositiveFloat | None = Field(None, description="± tolerance of the size or position (µm)")


class CircleFeature(_Feature):
    """A bore or boss."""

    type: Literal["circle"]
    center_mm: Point = Field(description="nominal centre [x, y] (mm)")
    diameter_mm: PositiveFloat = Field(le=MAX_MM, description="nominal diameter (mm)")


class LineFeature(_Feature):
    """A straight wall."""

    type: Literal["line"]
    from_mm: Point = Field(description="the nominal wall's start [x, y] (mm)")
    to_mm: Point = Field(description="its end [x, y] (mm)")


class WidthFeature(_Feature):
    """A slot's or pocket's width across the line from_mm to to_mm."""

    type: Literal["width"]
    from_mm: Point = Field(description="a point [x, y] beyond one wall (mm)")
    to_mm: Point = Field(description="a point [x, y] beyond the other (mm)")
    width_mm: PositiveFloat = Field(le=MAX_MM, description="nominal width (mm)")


def fit_circle(points: np.ndarray) -> tuple[np.ndarray, float, np.ndarray]:
    """The least-squares circle through ``points`` (mm): centre, radius and the residuals."""
    x, y = points[:, 0], points[:, 1]
    # algebraic start: x^2 + y^2 = 2 a x + 2 b y + c
    a, b, c = np.linalg.lstsq(np.column_stack([2 * x, 2 * y, np.ones_like(x)]), x**2 + y**2, rcond=None)[0]
    start = np.array([a, b, math.sqrt(max(c + a * a + b * b, 0.0))])
    fit = least_squares(lambda p: np.hypot(x - p[0], y - p[1]) - p[2], start, xtol=1e-15, ftol=1e-15, gtol=1e-15)
    centre, radius = fit.x[:2], float(fit.x[2])
    return centre, radius, np.hypot(x - centre[0], y - centre[1]) - radius


def _verdict(deviation_um: float, tolerance_um: float | None) -> bool | None:
    return None if tolerance_um is None else bool(abs(deviation_um) <= tolerance_um)


def not_found(feature: InspectSpec, message: str) -> FeatureNotFound:
    """A feature that could not be measured, with why."""
    return FeatureNotFound(name=feature.name, type=FeatureType(feature.type), z_mm=feature.z_mm, message=message)


def _circle_hits(centre: np.ndarray, radius_mm: float, origin: np.ndarray, direction: np.ndarray) -> np.ndarray:
    """Where the line ``origin + t direction`` (unit) meets the circle (mm): the values of t, none,
    one or two."""
    offset = origin - centre
    b = float(offset @ direction)
    disc = b * b - (float(offset @ offset) - radius_mm**2)
    return np.array([]) if disc < 0.0 else -b + np.array([-1.0, 1.0]) * math.sqrt(disc)


def _gap_ends(part: MachinedPart, z_mm: float, middle: np.ndarray, ends: tuple) -> list | None:
    """Where the line from ``middle`` towards each of ``ends`` first meets material (mm): the
    stock's outline or the side of the capsule nearest the first probe in material; that end
    itself where the line reaches it without; None when ``middle`` is in material.  Both rays
    are probed at once (one stream of the actual path)."""
    rays = []
    for end in ends:
        length = float(np.linalg.norm(end - middle))
        direction = (end - middle) / length
        at = np.arange(0.0, length + PROBE_STEP_MM, PROBE_STEP_MM).clip(max=length)
        rays.append((direction, middle + at[:, None] * direction))
    pts = np.concatenate([ray for _, ray in rays])
    found = part.probe(pts, z_mm)
    in_stock = shapely.contains_xy(part.stock, pts[:, 0], pts[:, 1])
    material = in_stock & (found.distance > 0.0)
    if material[0]:  # each ray starts at the middle
        return None
    out, first = [], 0
    for (direction, ray), end in zip(rays, ends):
        span = slice(first, first + len(ray))
        first += len(ray)
        hits = np.flatnonzero(material[span])
        if len(hits) == 0:
            out.append(end)
            continue
        k = int(hits[0])
        if not in_stock[span][k - 1]:  # the stock's own outline
            crossing = shapely.intersection(shapely.LineString([ray[k - 1], ray[k]]), part.stock.boundary)
            out.append(shapely.get_coordinates(crossing)[0])
            continue
        axis, reach = found.axis[span][k], float(found.reach[span][k])
        back = _circle_hits(axis, reach, ray[k], -direction) if np.isfinite(axis[0]) else np.array([])
        back = back[back >= -1e-9]
        out.append(ray[k] - direction * float(back.min()) if len(back) else ray[k])
    return out


def _measure_circle(feature: CircleFeature, part: MachinedPart) -> CircleMeasured | FeatureNotFound:
    centre, r = np.asarray(feature.center_mm), feature.diameter_mm / 2
    band = min(BAND_MM, r / 2)
    turn = np.arange(0.0, 2 * math.pi, PROBE_STEP_MM / r)
    found = part.probe(centre + r * np.column_stack([np.cos(turn), np.sin(turn)]), feature.z_mm, band)
    near = np.abs(found.distance) < band
    pts = found.surface()[near]
    if len(pts) < MIN_POINTS:
        return not_found(feature, f"no wall within {band} mm of the circle")
    fitted, radius, residual = fit_circle(pts)
    deviation = (2 * radius - feature.diameter_mm) * 1e3
    return CircleMeasured(
        **_measured(feature, deviation),
        diameter_mm=round(2 * radius, 6),
        center_mm=_point(fitted),
        roundness_um=round(float(np.ptp(residual) * 1e3), 3),
    )


def _measure_line(feature: LineFeature, part: MachinedPart) -> LineMeasured | FeatureNotFound:
    a, b = np.asarray(feature.from_mm), np.asarray(feature.to_mm)
    if np.allclose(a, b):
        return not_found(feature, "from_mm and to_mm are one point")
    u = (b - a) / np.linalg.norm(b - a)
    n = np.array([-u[1], u[0]])
    along = np.arange(0.0, np.linalg.norm(b - a) + PROBE_STEP_MM / 2, PROBE_STEP_MM)
    found = part.probe(a + along[:, None] * u, feature.z_mm, BAND_MM)
    near = np.abs(found.distance) < BAND_MM
    pts = found.surface()[near]
    if len(pts) < MIN_POINTS:
        return not_found(feature, f"no wall within {BAND_MM} mm of the line")
    mean = pts.mean(axis=0)
    direction = np.linalg.svd(pts - mean)[2][0]
    normal = np.array([-direction[1], direction[0]])
    residual = (pts - mean) @ normal
    middle = 0.5 * (a + b)
    on_fit = mean + direction * ((middle - mean) @ direction)  # the middle's foot on the fit
    # the material's side: +1 where it lies along n (away from the tools' axes); material
    # left moves the wall against it
    side = 1.0 if float(np.mean((found.xy[near] - found.axis[near]) @ n)) > 0.0 else -1.0
    deviation = -side * float((on_fit - middle) @ n) * 1e3
    return LineMeasured(
        **_measured(feature, deviation),
        position_mm=_point(on_fit),
        straightness_um=round(float(np.ptp(residual) * 1e3), 3),
    )


def _measure_width(feature: WidthFeature, part: MachinedPart) -> WidthMeasured | FeatureNotFound:
    a, b = np.asarray(feature.from_mm), np.asarray(feature.to_mm)
    middle = 0.5 * (a + b)
    gap = None if np.allclose(a, b) else _gap_ends(part, feature.z_mm, middle, (a, b))
    if gap is None:
        return not_found(feature, "the line's middle is in material: no gap across it")
    width = float(np.linalg.norm(gap[1] - gap[0]))
    deviation = (width - feature.width_mm) * 1e3
    return WidthMeasured(
        **_measured(feature, deviation), width_mm=round(width, 6), center_mm=_point(0.5 * (gap[0] + gap[1]))
    )


def _point(xy: np.ndarray) -> tuple[float, float]:
    """A measured point [x, y] (mm) to 6 decimals."""
    return round(float(xy[0]), 6), round(float(xy[1]), 6)


def _measured(feature, deviation_um: float) -> dict:
    """What every measured feature reports: its name, height, deviation (µm) and verdict."""
    return {
        "name": feature.name,
        "z_mm": feature.z_mm,
        "deviation_um": round(deviation_um, 3),
        "passed": _verdict(deviation_um, feature.tolerance_um),
    }


#: The feature types by name (``[[inspect]] type = ...``, :class:`~twin.records.FeatureType`):
#: each entry's settings are its spec, its value its measurement ``measure(feature, part)``, its
#: summary the spec's docstring: the one place the types are told apart.
FEATURES: Registry[Callable[[Any, MachinedPart], Inspected]] = Registry("inspection feature")
register_kind(FEATURES, FeatureType.CIRCLE, CircleFeature, _measure_circle)
register_kind(FEATURES, FeatureType.LINE, LineFeature, _measure_line)
register_kind(FEATURES, FeatureType.WIDTH, WidthFeature, _measure_width)

#: An ``[[inspect]]`` table: one spec per feature type of :data:`FEATURES`, told apart by
#: ``type``; to a type checker, which cannot follow a union built at run time, their union.
if TYPE_CHECKING:
    InspectSpec = CircleFeature | LineFeature | WidthFeature
else:
    InspectSpec = tagged_union(FEATURES)


def measure(feature: InspectSpec, part: MachinedPart) -> Inspected:
    """One feature of ``inspection`` measured on the actual ``part`` at its height (see the
    module docstring): probes every :data:`PROBE_STEP_MM` along the nominal feature."""
    return FEATURES[feature.type].value(feature, part)


def inspect(features: Sequence[InspectSpec], part: MachinedPart, stock: StockSpec) -> tuple[Inspected, ...]:
    """Each of ``features`` measured on the actual ``part`` at its height (:func:`measure`), or
    why it cannot be: a height outside the ``stock``."""
    return tuple(
        measure(feature, part)
        if stock.bottom_mm <= feature.z_mm <= stock.top_mm
        else not_found(
            feature, f"z_mm {feature.z_mm:g} is outside the stock (Z {stock.bottom_mm:g} to {stock.top_mm:g} mm)"
        )
        for feature in features
    )
