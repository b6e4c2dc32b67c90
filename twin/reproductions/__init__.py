"""The papers' reproductions, one package per paper named as in :mod:`controllers.papers`, each
registering a :class:`~twin.reproductions.base.Reproduction` (every paper's package is imported
below, in the order of the source texts, so a new reproduction is one new package, its name in
:data:`controllers.papers.PAPERS` and its tests); ``twin reproduce PAPER`` and ``twin.reproduce``
dispatch through :data:`REPRODUCTIONS`, ``twin sweep`` asks each for certificates.
"""

from __future__ import annotations

import importlib

from controllers.papers import PAPERS
from twin.reproductions.base import REPRODUCTIONS, Reproduction, register_reproduction

for _paper in PAPERS:
    importlib.import_module(f"{__name__}.{_paper}")

#: ``twin reproduce``'s defaults: Monte Carlo samples, random twin samples, seed.
DEFAULT_SAMPLES, DEFAULT_TWIN_SAMPLES, DEFAULT_SEED = 1000, 20, 0


def twin_vs_tf(label: str, twin: dict, tf: dict, keys, tol_rel: float) -> list[str]:
    """The ``keys`` whose twin value departs from the transfer-function value by more than
    ``tol_rel`` of it, one line each, prefixed by ``label``."""
    return [
        f"{label}: {key} twin {twin[key]:.4g} vs TF {tf[key]:.4g}"
        for key in keys
        if abs(twin[key] - tf[key]) > tol_rel * abs(tf[key])
    ]


def reproduction(paper: str) -> Reproduction:
    """The reproduction of ``paper`` (e.g. ``choi1999``)."""
    return REPRODUCTIONS[paper]


def certificates(machine: str, controller: str | None, symbols: set[str], others: list[str]) -> list[dict]:
    """Every reproduction's robustness certificates for ``controller`` on ``machine`` when a
    sweep varies the machine parameters ``symbols`` (and the other scenario paths ``others``)."""
    return [c for r in REPRODUCTIONS.values() for c in r.certificates(machine, controller, symbols, others)]


__all__ = [
    "DEFAULT_SAMPLES",
    "DEFAULT_SEED",
    "DEFAULT_TWIN_SAMPLES",
    "REPRODUCTIONS",
    "Reproduction",
    "certificates",
    "register_reproduction",
    "reproduction",
    "twin_vs_tf",
]
