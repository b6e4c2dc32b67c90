"""Anang 2017: the :class:`~twin.reproductions.base.Reproduction` ``twin reproduce anang2017`` runs.

:mod:`.procedure` computes (margins, Popov bound, critical gains, Tables 1-3 on the
transfer-function loop and the twin); :mod:`.report` prints and plots.  ``samples`` and
``seed`` do not apply (nothing is random); ``twin_samples = 0`` leaves the twin out.
"""

from __future__ import annotations

from twin.reproductions.base import Reproduction, register_reproduction


@register_reproduction
class Anang2017(Reproduction):
    """Anang et al. (2017): PID margins, the nonlinear PID and its Popov bound, sine tracking while milling."""

    name = "anang2017"
    report_module = "twin.reproductions.anang2017.report"
