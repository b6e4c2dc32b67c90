"""Inspection of the virtual part as a coordinate measuring machine reports it.

Each ``[[inspect]]`` feature names a place on the nominal part; it is measured on the actual
part's section at its ``z_mm`` (:mod:`twin.process.part`), from points every
:data:`PROBE_STEP_MM` along the section's boundary within :data:`BAND_MM` of the nominal
feature:

- ``circle`` (a bore or a boss): the least-squares circle (geometric, scipy's
  ``least_squares`` from the algebraic fit); its diameter, centre and roundness (the spread of
  the radial residuals, peak to valley);
- ``line`` (a wall from ``from_mm`` to ``to_mm``): the least-squares line (total, through the
  points' principal axis); its position where the nominal line's middle falls on it, the signed
  offset from the nominal (positive: material left) and straightness (peak to valley);
- ``width`` (a slot or pocket): the two-point size along the line ``from_mm`` to ``to_mm``
  across it: the length of the open gap that holds the line's middle.

``deviation_um`` is the measured less the nominal; ``pass`` holds it within ``tolerance_um``.
"""

from __future__ import annotations

import math
from typing import Annotated, Literal

import numpy as np
import shapely
from pydantic import Field, PositiveFloat
from scipy.optimize import least_squares

from twin.process.part import points_along
from twin.spec import MAX_MM, Millimetres, StrictSpec

#: Distance from a nominal feature (mm) within which the boundary counts as its points.
BAND_MM = 0.5
#: Spacing of the probed points along the boundary (mm).
PROBE_STEP_MM = 0.02
#: Points a feature needs to be measured.
MIN_POINTS = 8
#: A point [x, y] of a feature (mm).
Point = tuple[Millimetres, Millimetres]


class _Feature(StrictSpec):
    name: str = Field(min_length=1, max_length=200, description="the feature's name in the report")
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
    """A slot's or pocket's width across the line ``from_mm`` to ``to_mm``."""

    type: Literal["width"]
    from_mm: Point = Field(description="a point [x, y] beyond one wall (mm)")
    to_mm: Point = Field(description="a point [x, y] beyond the other (mm)")
    width_mm: PositiveFloat = Field(le=MAX_MM, description="nominal width (mm)")


InspectSpec = Annotated[CircleFeature | LineFeature | WidthFeature, Field(discriminator="type")]


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


def not_found(feature, message: str) -> dict:
    """The row of a feature that could not be measured, with why."""
    return {
        "name": feature.name,
        "type": feature.type,
        "z_mm": feature.z_mm,
        "found": False,
        "message": message,
        "pass": False,
    }


def measure(feature, material: shapely.Geometry) -> dict:
    """One feature of ``inspection`` measured on the section ``material`` at its height."""
    row: dict = {"name": feature.name, "type": feature.type, "z_mm": feature.z_mm}
    if feature.type == "circle":
        centre, r = np.asarray(feature.center_mm), feature.diameter_mm / 2
        band = min(BAND_MM, r / 2)
        zone = (
            shapely.Point(centre)
            .buffer(r + band, quad_segs=256)
            .difference(shapely.Point(centre).buffer(r - band, quad_segs=256))
        )
        pts = points_along(shapely.intersection(material.boundary, zone), PROBE_STEP_MM)
        if len(pts) < MIN_POINTS:
            return not_found(feature, f"no wall within {band} mm of the circle")
        fitted, radius, residual = fit_circle(pts)
        deviation = (2 * radius - feature.diameter_mm) * 1e3
        row |= {
            "diameter_mm": round(2 * radius, 6),
            "center_mm": [round(float(v), 6) for v in fitted],
            "roundness_um": round(float(np.ptp(residual) * 1e3), 3),
        }
    elif feature.type == "line":
        a, b = np.asarray(feature.from_mm), np.asarray(feature.to_mm)
        if np.allclose(a, b):
            return not_found(feature, "from_mm and to_mm are one point")
        u = (b - a) / np.linalg.norm(b - a)
        n = np.array([-u[1], u[0]])
        zone = shapely.buffer(shapely.LineString([a, b]), BAND_MM, cap_style="flat")
        pts = points_along(shapely.intersection(material.boundary, zone), PROBE_STEP_MM)
        if len(pts) < MIN_POINTS:
            return not_found(feature, f"no wall within {BAND_MM} mm of the line")
        mean = pts.mean(axis=0)
        direction = np.linalg.svd(pts - mean)[2][0]
        normal = np.array([-direction[1], direction[0]])
        residual = (pts - mean) @ normal
        middle = 0.5 * (a + b)
        on_fit = mean + direction * ((middle - mean) @ direction)  # the middle's foot on the fit
        # the material's side: +1 where it lies along n; material left moves the wall against it
        side = 1.0 if material.contains(shapely.Point(on_fit + BAND_MM * n)) else -1.0
        deviation = -side * float((on_fit - middle) @ n) * 1e3
        row |= {
            "position_mm": [round(float(v), 6) for v in on_fit],
            "straightness_um": round(float(np.ptp(residual) * 1e3), 3),
        }
    else:
        a, b = np.asarray(feature.from_mm), np.asarray(feature.to_mm)
        middle = shapely.Point(0.5 * (a + b))
        gaps = shapely.get_parts(shapely.difference(shapely.LineString([a, b]), material))
        gap = min(gaps, key=lambda g: g.distance(middle), default=None) if len(gaps) else None
        if gap is None or gap.distance(middle) > 0.0 or gap.length == 0.0:
            return not_found(feature, "the line's middle is in material: no gap across it")
        deviation = (gap.length - feature.width_mm) * 1e3
        row |= {
            "width_mm": round(gap.length, 6),
            "center_mm": [round(float(v), 6) for v in shapely.get_coordinates(gap.centroid)[0]],
        }
    return {**row, "deviation_um": round(deviation, 3), "pass": _verdict(deviation, feature.tolerance_um)}
