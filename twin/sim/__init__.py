"""The physics loop, drive and sensors: :func:`simulate` runs a closed loop on a machine."""

from twin.sim.drive import Drive, Encoder
from twin.sim.runner import RunResult, simulate

__all__ = ["Drive", "Encoder", "RunResult", "simulate"]
