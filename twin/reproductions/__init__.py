"""Each paper's reproduction, one package per seed, behind one registry.

A reproduction package offers ``run(samples, twin_samples, seed, progress) -> dict``,
``format_report(results) -> str``, ``write_plots(folder, results) -> list of Path`` (``results``: what
``run`` returned, for the plots that need it), ``record(path)`` and
``failed(results) -> bool``, ``markdown_tables(results) -> dict`` (the docs page's tables) and,
where the paper gives one, ``certificates(machine, controller, symbols, others) -> list of
dict`` (a robustness certificate over a parameter box, which ``twin sweep`` prints beside its
evidence); ``twin reproduce SEED`` dispatches through :data:`REPRODUCTIONS`.
"""

from __future__ import annotations

import importlib

#: Seed name -> package of its reproduction.
REPRODUCTIONS = {
    "seed000": "twin.reproductions.seed000",
    "seed001": "twin.reproductions.seed001",
    "seed002": "twin.reproductions.seed002",
    "seed003": "twin.reproductions.seed003",
    "seed004": "twin.reproductions.seed004",
}


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


def reproduction(seed: str):
    """The reproduction package of ``seed`` (imported on demand)."""
    return importlib.import_module(REPRODUCTIONS[seed])


def certificates(machine: str, controller: str | None, symbols: set[str], others: list[str]) -> list[dict]:
    """Every reproduction's robustness certificates for ``controller`` on ``machine`` when a
    sweep varies the machine parameters ``symbols`` (and the other scenario paths ``others``):
    each package's ``certificates`` hook, where it has one."""
    out = []
    for seed in REPRODUCTIONS:
        hook = getattr(reproduction(seed), "certificates", None)
        if hook is not None:
            out += hook(machine, controller, symbols, others)
    return out
