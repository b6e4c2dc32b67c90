"""Yadav 2020: the :class:`~twin.reproductions.base.Reproduction` ``twin reproduce yadav2020`` runs.

:mod:`.procedure` computes (interval model, designs, Table 2 on the transfer functions and the
twin, disturbance runs); :mod:`.report` prints and plots.
"""

from __future__ import annotations

from twin.reproductions.base import Reproduction, register_reproduction


@register_reproduction
class Yadav2020(Reproduction):
    """Yadav, Pathak, Gaur (2020): robust PI, IMC and H-infinity on a lead-screw axis.

    Kharitonov over the interval model, Table 2 on the transfer functions and the twin.
    """

    name = "yadav2020"
    report_module = "twin.reproductions.yadav2020.report"

    def certificates(self, machine: str, controller: str | None, symbols: set[str], others: list[str]) -> list[dict]:
        """See :func:`.report.certificates`."""
        return self.report().certificates(machine, controller, symbols, others)
