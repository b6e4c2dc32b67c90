"""The papers' reproductions, one package per seed, each registering a
:class:`~twin.reproductions.base.Reproduction` (every package here is imported below, so a new
reproduction is one new package and its tests); ``twin reproduce SEED`` and ``twin.reproduce``
dispatch through :data:`REPRODUCTIONS`, ``twin sweep`` asks each for certificates.
"""

from __future__ import annotations

import importlib
import pkgutil

from twin.reproductions.base import REPRODUCTIONS, Reproduction, register_reproduction

for _module in pkgutil.iter_modules(__path__):
    if _module.ispkg:
        importlib.import_module(f"{__name__}.{_module.name}")

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


def reproduction(seed: str) -> Reproduction:
    """The reproduction of ``seed``."""
    return REPRODUCTIONS[seed]


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
