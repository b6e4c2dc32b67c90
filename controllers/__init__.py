"""Control side of the twin: block kinds on a signal bus, design procedures, the papers' controllers.

Never imports mujoco: every block runs on python-control models and plain arrays alone.
Importing it registers every controller and observer kind (:mod:`controllers.kinds`).
"""

import controllers.kinds  # noqa: F401 (registers the kinds)
from controllers.blocks import BlockProgram, Controller, error_feedback, open_loop
from controllers.registry import CONTROLLERS, OBSERVERS, make_controller

__all__ = ["CONTROLLERS", "OBSERVERS", "BlockProgram", "Controller", "error_feedback", "make_controller", "open_loop"]
