"""What every paper's reproduction is: a :class:`Reproduction` registered under its paper's name,
and the comparison every one of them makes (:func:`twin_vs_tf`)."""

from __future__ import annotations

import importlib
from pathlib import Path
from types import ModuleType

from controllers.registries import Registry


class Reproduction:
    """A paper's reproduction.  Subclasses (one per paper package) set :attr:`name`,
    :attr:`report_module` and a docstring whose first line is the docs line.

    The report module offers ``run(samples, twin_samples, seed, progress) -> dict`` (every
    number, JSON-ready, with ``twin_vs_tf_mismatches``), ``format_report(results) -> str``,
    ``markdown_tables(results) -> dict`` (the docs page's tables), ``write_plots(folder,
    results) -> list of Path`` and ``twin_runs() -> dict of RunResult`` (what ``--rrd``
    records); it is imported on first use, so listing the reproductions stays cheap.
    """

    #: The paper's name (``twin reproduce <name>``).
    name: str = ""
    #: The module that computes, prints and plots.
    report_module: str = ""

    @property
    def doc(self) -> str:
        """The docs line: the first line of the class docstring."""
        return (type(self).__doc__ or self.name).strip().splitlines()[0]

    def report(self) -> ModuleType:
        """The report module (imported now)."""
        return importlib.import_module(self.report_module)

    def run(self, samples: int, twin_samples: int, seed: int, progress: bool) -> dict:
        """Every number of the reproduction: ``samples`` Monte Carlo samples on the transfer
        functions, ``twin_samples`` random twin samples (0 leaves the twin out), ``seed`` of
        the draws."""
        return self.report().run(samples, twin_samples, seed, progress)

    def format_report(self, results: dict) -> str:
        """The text tables: paper | transfer function | twin."""
        return self.report().format_report(results)

    def markdown_tables(self, results: dict) -> dict[str, str]:
        """The docs page's generated tables by name."""
        return self.report().markdown_tables(results)

    def write_plots(self, folder: Path, results: dict) -> list[Path]:
        """PNG figures as the paper's, written into ``folder``."""
        return self.report().write_plots(folder, results)

    def record(self, path: Path) -> None:
        """A Rerun recording of the reproduction's twin runs."""
        from twin.recording import record_runs

        record_runs(self.report().twin_runs(), path)

    def failed(self, results: dict) -> bool:
        """Whether a twin number departs from its transfer-function number by more than its
        tolerance (2 %)."""
        return bool(results["twin_vs_tf_mismatches"])

    def certificates(self, machine: str, controller: str | None, symbols: set[str], others: list[str]) -> list[dict]:
        """The paper's robustness certificates for ``controller`` on ``machine`` when a sweep
        varies the machine parameters ``symbols`` and the other scenario paths ``others``
        (``twin sweep`` prints them beside its evidence); none by default."""
        return []


#: Reproductions by paper name, as their packages are imported (in whatever order a process
#: imports them); :data:`twin.reproductions.registry.REPRODUCTIONS` holds them all in the order
#: of the source texts.
REGISTERED: Registry[Reproduction] = Registry("reproduction")


def register_reproduction(cls: type[Reproduction]) -> type[Reproduction]:
    """Class decorator: add an instance of ``cls`` to :data:`REGISTERED` under its name (its
    summary the docs line, :attr:`Reproduction.doc`).

    Raises
    ------
    ValueError
        A class without a name, or a name registered already.
    """
    paper = cls()
    REGISTERED.add(cls.name, paper, summary=paper.doc)
    return cls


def twin_vs_tf(label: str, twin: dict, tf: dict, *, keys, tol_rel: float) -> list[str]:
    """The ``keys`` whose twin value departs from the transfer-function value by more than
    ``tol_rel`` of it, one line each, prefixed by ``label``."""
    return [
        f"{label}: {key} twin {twin[key]:.4g} vs TF {tf[key]:.4g}"
        for key in keys
        if abs(twin[key] - tf[key]) > tol_rel * abs(tf[key])
    ]


def mismatch_lines(heading: str, mismatches: list[str]) -> list[str]:
    """The text report's closing lines: ``heading`` (what was compared, with its tolerance), then
    "all within" or each twin number outside its tolerance (:func:`twin_vs_tf`)."""
    verdict = "all within" if not mismatches else f"{len(mismatches)} outside:"
    return ["", f"{heading}: {verdict}", *(f"  {m}" for m in mismatches)]
