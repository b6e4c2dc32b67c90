"""Choi 1999: the :class:`~twin.reproductions.base.Reproduction` ``twin reproduce choi1999`` runs.

:mod:`.procedure` computes (loop-shaping design, reduction, PID, mu analysis and sampled
plants, ZPETC, the circle tests on the transfer functions and the twin); :mod:`.report`
prints and plots.  ``samples`` random plants per controller beside the 1024 corners;
``twin_samples = 0`` leaves the twin out.
"""

from __future__ import annotations

from twin.reproductions.base import Reproduction, register_reproduction


@register_reproduction
class Choi1999(Reproduction):
    """Choi, Hong, Kim, Kim (1999): MIMO H-infinity loop shaping, mu and ZPETC.

    On the linear-motor XY table, with the PID pair it is compared with.
    """

    name = "choi1999"
    report_module = "twin.reproductions.choi1999.report"

    def certificates(self, machine: str, controller: str | None, symbols: set[str], others: list[str]) -> list[dict]:
        """See :func:`.report.certificates`."""
        return self.report().certificates(machine, controller, symbols, others)
