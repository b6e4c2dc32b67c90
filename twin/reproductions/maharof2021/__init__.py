"""Maharof 2021: the :class:`~twin.reproductions.base.Reproduction` ``twin reproduce maharof2021`` runs.

:mod:`.procedure` computes (cascade design, IMBDO Q-filter, the numerical cases on the
transfer-function loop and the twin); :mod:`.report` prints and plots.  ``samples`` and
``seed`` do not apply; ``twin_samples = 0`` leaves the twin out.
"""

from __future__ import annotations

from twin.reproductions.base import Reproduction, register_reproduction


@register_reproduction
class Maharof2021(Reproduction):
    """Maharof 2021: cascade P/PI with inverse-model and harmonic disturbance observers."""

    name = "maharof2021"
    report_module = "twin.reproductions.maharof2021.report"
