"""CNC feed-drive digital twin: MuJoCo XY tables, the source papers' controllers, recordings.

The public API (:mod:`twin.api`) is imported on first use, so that ``import twin`` and the
command line start fast::

    import twin
    run = twin.run("choi1999_mimo_cutting", duration_s=0.5)
    run.summary, run.to_pandas()

``twin.load``, ``twin.run``, ``twin.sweep``, ``twin.fidelity``, ``twin.reproduce``,
``twin.program`` (a part program read and planned, as ``twin gcode``), ``twin.frf``,
``twin.calibrate`` and ``twin.tune`` (a machine's FRF, calibration and tuning), ``twin.lobes``
(a tool's stability lobes), and what they return (:mod:`twin.results`): ``twin.Run``,
``twin.Sweep``, ``twin.Program``, ``twin.Frf``, ``twin.Calibration``, ``twin.Tuning``,
``twin.StabilityLobes`` and ``twin.Fidelity``; errors are :class:`twin.errors.TwinInputError` and
:class:`twin.errors.SimulationDiverged`.
"""

from __future__ import annotations

__all__ = [
    "Calibration",
    "Fidelity",
    "Frf",
    "Program",
    "Run",
    "StabilityLobes",
    "Sweep",
    "Tuning",
    "calibrate",
    "fidelity",
    "frf",
    "load",
    "lobes",
    "program",
    "reproduce",
    "run",
    "sweep",
    "tune",
]


def __getattr__(name: str):
    """``twin.run`` and the other names of :data:`__all__`, from :mod:`twin.api` (PEP 562)."""
    if name in __all__:
        from twin import api

        return getattr(api, name)
    raise AttributeError(f"module 'twin' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted([*globals(), *__all__])
