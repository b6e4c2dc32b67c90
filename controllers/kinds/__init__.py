"""Every controller and observer kind: the generic families and observers here, one module per
family, and each paper's own kinds in ``controllers/papers/<paper>/kinds.py``.  Each registers
itself in :data:`controllers.registry.CONTROLLERS` or :data:`~controllers.registry.OBSERVERS` at
import, and every module is imported below, so a new kind is one new module (and its tests)."""

import importlib
import pkgutil

from controllers.papers import PAPERS

for _module in pkgutil.iter_modules(__path__):
    importlib.import_module(f"{__name__}.{_module.name}")
for _paper in PAPERS:
    importlib.import_module(f"controllers.papers.{_paper}.kinds")
