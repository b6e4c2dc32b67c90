"""Control side of the twin: discrete-time control blocks and the papers' controllers.

Never imports mujoco: every block is usable against python-control models alone.
"""

from controllers.base import ControlBlock
from controllers.lti import DiscreteLTI
from controllers.registry import CONTROLLERS, make_controller

__all__ = ["ControlBlock", "DiscreteLTI", "CONTROLLERS", "make_controller"]
