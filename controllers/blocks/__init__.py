"""Block kinds (:mod:`.core`), the signal bus (:mod:`.signals`), composition (:mod:`.compose`)
and compilation onto the bus (:mod:`.program`)."""

from controllers.blocks.compose import (
    cascade,
    error_feedback,
    harmonic_estimator,
    harmonic_observer,
    inverse_model_observer,
    lti_block,
    lure,
    open_loop,
    relay_feedback,
    rename,
    sum_of,
    with_correction,
    with_feedforward,
)
from controllers.blocks.core import NONLINEARITIES, Controller, Linear, PythonBlock, Sequence, Static, Sum
from controllers.blocks.program import BlockProgram, SignalError
from controllers.blocks.signals import AXIS_SIGNALS, preview_ticks_needed, standard_signals

__all__ = [
    "AXIS_SIGNALS",
    "NONLINEARITIES",
    "BlockProgram",
    "Controller",
    "Linear",
    "PythonBlock",
    "Sequence",
    "SignalError",
    "Static",
    "Sum",
    "cascade",
    "error_feedback",
    "harmonic_estimator",
    "harmonic_observer",
    "inverse_model_observer",
    "lti_block",
    "lure",
    "open_loop",
    "preview_ticks_needed",
    "relay_feedback",
    "rename",
    "standard_signals",
    "sum_of",
    "with_correction",
    "with_feedforward",
]
