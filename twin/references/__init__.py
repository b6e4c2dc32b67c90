"""Reference signals: position with velocity and acceleration for feedforward.

Every reference has ``n_axes`` and ``sample(t) -> ndarray (len(t), n_axes, 3)`` with columns
position (m), velocity (m/s), acceleration (m/s^2).  One-axis signals (step, ramp, sines) drive
the axes listed in ``axes`` (indices) and hold the others at zero; paths (circle, square,
polyline) need two axes and are given in mm and mm/min as machinists state them.

Each kind lives in one module of this package that registers its scenario spec and builder
(:func:`twin.references.kinds.register`); every module here is imported below, so a new
reference kind is one new module (and its tests): the scenario schema, ``twin list`` and the
runs read :data:`REFERENCES`.
"""

from __future__ import annotations

import importlib
import pkgutil

from twin.references.kinds import REFERENCES, ReferenceContext, ReferenceSpecBase, register
from twin.references.paths import Circle, Polyline, square
from twin.references.sines import MAX_SINES, SumOfSines
from twin.references.step import Ramp, Step

for _module in pkgutil.iter_modules(__path__):
    importlib.import_module(f"{__name__}.{_module.name}")

__all__ = [
    "MAX_SINES",
    "REFERENCES",
    "Circle",
    "Polyline",
    "Ramp",
    "ReferenceContext",
    "ReferenceSpecBase",
    "Step",
    "SumOfSines",
    "register",
    "square",
]
