"""Every controller and observer kind, one module per family; each registers itself in
:data:`controllers.registry.CONTROLLERS` or :data:`~controllers.registry.OBSERVERS` at import,
and every module here is imported below, so a new kind is one new module (and its tests)."""

import importlib
import pkgutil

for _module in pkgutil.iter_modules(__path__):
    importlib.import_module(f"{__name__}.{_module.name}")
