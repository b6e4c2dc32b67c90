"""Control side of the twin: block kinds on a signal bus, design procedures, the papers' controllers.

Never imports mujoco: every block runs on python-control models and plain arrays alone.
The names below load on first use (PEP 562): the registry's import registers every controller and
observer kind (:mod:`controllers.kinds`), while importing :mod:`controllers.registries` alone (the
registry type the twin's own registries share) loads nothing else.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from controllers.blocks import BlockProgram, Controller, error_feedback, open_loop
    from controllers.registry import CONTROLLERS, OBSERVERS, make_controller

#: Each public name and the module that defines it.
_HOMES = {
    "BlockProgram": "controllers.blocks",
    "Controller": "controllers.blocks",
    "error_feedback": "controllers.blocks",
    "open_loop": "controllers.blocks",
    "CONTROLLERS": "controllers.registry",
    "OBSERVERS": "controllers.registry",
    "make_controller": "controllers.registry",
}

__all__ = ["CONTROLLERS", "OBSERVERS", "BlockProgram", "Controller", "error_feedback", "make_controller", "open_loop"]


def __getattr__(name: str) -> Any:
    """Load ``name`` from its module (PEP 562)."""
    if name not in _HOMES:
        raise AttributeError(f"module 'controllers' has no attribute {name!r}")
    return getattr(importlib.import_module(_HOMES[name]), name)
