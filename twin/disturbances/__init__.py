"""The papers' disturbances, as the scenario's ``[[disturbances]]`` kinds: signals added to the
drive input (:mod:`.drive_input`) and the milling forces on the workpiece
(:mod:`.cutting_forces`, whose models and compiled kernels are :mod:`twin.machining.cutting`).

Each kind registers its scenario spec and builder (:func:`twin.disturbances.kinds.register`);
every module here is imported below, so a new disturbance kind is one new module (and its tests):
the scenario schema, ``twin list`` and the runs read :data:`DISTURBANCES`.
"""

from __future__ import annotations

import importlib
import pkgutil

from twin.disturbances.kinds import DISTURBANCES, DisturbanceSpecBase, register

for _module in pkgutil.iter_modules(__path__):
    importlib.import_module(f"{__name__}.{_module.name}")

__all__ = ["DISTURBANCES", "DisturbanceSpecBase", "register"]
