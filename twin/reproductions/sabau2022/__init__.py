"""Sabau 2022: the :class:`~twin.reproductions.base.Reproduction` ``twin reproduce sabau2022`` runs.

:mod:`.procedure` computes (relay test and Ziegler-Nichols, cascades, state feedback by pole
placement, LQR and LMI regions with their cascades, the fractional PI and the structured-mu
cascade, the bee colony, the trajectories of Table 2, on the transfer functions and the
twin); :mod:`.report` prints and plots.
"""

from __future__ import annotations

from twin.reproductions.base import Reproduction, register_reproduction


@register_reproduction
class Sabau2022(Reproduction):
    """Sabau (2022): classical to advanced control of two coupled identified axes.

    From the relay test and Ziegler-Nichols to LMI regions and the fractional PI.
    """

    name = "sabau2022"
    report_module = "twin.reproductions.sabau2022.report"
