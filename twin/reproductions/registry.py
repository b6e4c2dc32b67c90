"""Every paper's reproduction, registered: importing this module imports each paper's package
(in the order of the source texts, :data:`controllers.papers.PAPERS`)."""

from __future__ import annotations

import importlib

from controllers.papers import PAPERS
from controllers.registries import Registry
from twin.reproductions.base import REGISTERED, Reproduction

for _paper in PAPERS:
    importlib.import_module(f"twin.reproductions.{_paper}")

#: Every reproduction by paper name, in the order of the source texts (whatever order a process
#: imported the packages in: a test may import one paper's before this module).
REPRODUCTIONS: Registry[Reproduction] = Registry("reproduction")
REPRODUCTIONS.update((paper, REGISTERED[paper]) for paper in PAPERS)


def reproduction(paper: str) -> Reproduction:
    """The reproduction of ``paper`` (e.g. ``choi1999``)."""
    return REPRODUCTIONS[paper].value


def certificates(machine: str, controller: str | None, symbols: set[str], others: list[str]) -> list[dict]:
    """Every reproduction's robustness certificates for ``controller`` on ``machine`` when a sweep
    varies the machine parameters ``symbols`` (and the other scenario paths ``others``)."""
    return [c for r in REPRODUCTIONS.values() for c in r.value.certificates(machine, controller, symbols, others)]


__all__ = ["REPRODUCTIONS", "certificates", "reproduction"]
