"""Markdown tables of the reproductions, generated from ``twin reproduce PAPER --json`` output.

The paper pages (``docs/pages/papers/<paper>.md``) hold blocks

    <!-- generated: anang2017.tables_1_3 -->
    | ... the table ... |
    <!-- end generated -->

whose content is what the paper's ``markdown_tables(results)`` renders for that name from the
reproduction's JSON (``docs/results/<paper>.json``, written by ``twin reproduce PAPER --json``
with its default settings).  No result number in those tables is typed by hand.

``python -m twin.reproductions.tables --write`` rewrites the blocks from the JSON files;
``--check`` exits 1 (naming the blocks) when a page differs from them; ``--rerun`` first runs
every reproduction again and writes its JSON (minutes), so ``--rerun --check`` verifies that
the committed results are what the code computes.  The committed results are computed with
OpenBLAS's Haswell kernels (``OPENBLAS_CORETYPE=Haswell``, as ``.ci/run`` sets): Choi 1999's
H-infinity design differs at 1e-4 with the AVX-512 kernels, and its air-cut runs in micrometres.
"""

from __future__ import annotations

import argparse
import json
import re
import sys
from pathlib import Path

from twin.reproductions import DEFAULT_SAMPLES, DEFAULT_SEED, DEFAULT_TWIN_SAMPLES
from twin.reproductions.registry import REPRODUCTIONS, reproduction

#: The repository's docs folder (this file is twin/reproductions/tables.py).
DOCS = Path(__file__).resolve().parents[2] / "docs"
_BLOCK = re.compile(r"(<!-- generated: (\w+)\.(\w+) -->\n)(.*?)(<!-- end generated -->)", re.S)


def markdown_table(header: list[str], rows: list[list[str]]) -> str:
    """A GitHub-flavoured Markdown table (cells already formatted; a ``|`` inside one is escaped),
    ending in a newline."""

    def line(cells):
        return "| " + " | ".join(str(c).replace("|", "\\|") for c in cells) + " |"

    return "\n".join([line(header), "|" + "---|" * len(header), *(line(row) for row in rows)]) + "\n"


def fmt(value, spec: str = ".3g", none: str = "–") -> str:
    """A number for a table: ``none`` for None or nan, else formatted with ``spec``."""
    if value is None or (isinstance(value, float) and value != value):
        return none
    return format(value, spec)


def pair(values, spec: str = ".3g", sep: str = " / ") -> str:
    """Per-axis values as ``a / b``."""
    return sep.join(fmt(v, spec) for v in values)


def results_path(paper: str, folder: Path | None = None) -> Path:
    """Where the committed JSON of ``paper`` lives."""
    return (folder or DOCS / "results") / f"{paper}.json"


def render(paper: str, results: dict) -> dict[str, str]:
    """Every generated table of ``paper`` by name."""
    return reproduction(paper).markdown_tables(results)


def fill(page: str, tables: dict[str, dict[str, str]]) -> tuple[str, list[str]]:
    """``page`` with every generated block replaced from ``tables[paper][name]``, and the names
    of the blocks whose content changed.

    Raises
    ------
    KeyError
        A block names a table that its paper does not render.
    """
    changed = []

    def replace(match):
        paper, name = match.group(2), match.group(3)
        body = tables[paper][name]
        if body != match.group(4):
            changed.append(f"{paper}.{name}")
        return match.group(1) + body + match.group(5)

    return _BLOCK.sub(replace, page), changed


def blocks(page: str) -> list[str]:
    """The ``paper.name`` of every generated block in ``page``."""
    return [f"{m.group(2)}.{m.group(3)}" for m in _BLOCK.finditer(page)]


def load_tables(folder: Path | None = None) -> dict[str, dict[str, str]]:
    """Every paper's tables, rendered from its JSON in ``folder`` (default ``docs/results``)."""
    return {paper: render(paper, json.loads(results_path(paper, folder).read_text())) for paper in REPRODUCTIONS}


def pages() -> list[Path]:
    """The pages that hold generated blocks."""
    return sorted(p for p in (DOCS / "pages" / "papers").glob("*.md") if p.stem in REPRODUCTIONS)


def _rerun(folder: Path) -> None:
    """Run every reproduction with ``twin reproduce``'s defaults and write its JSON into
    ``folder`` as ``twin reproduce PAPER --json`` prints it."""
    folder.mkdir(parents=True, exist_ok=True)
    for paper in REPRODUCTIONS:
        print(f"running twin reproduce {paper}", file=sys.stderr)
        res = reproduction(paper).run(DEFAULT_SAMPLES, DEFAULT_TWIN_SAMPLES, DEFAULT_SEED, progress=False)
        results_path(paper, folder).write_text(json.dumps(res, indent=1, default=float) + "\n")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m twin.reproductions.tables", description=__doc__.split("\n\n")[0])
    mode = parser.add_mutually_exclusive_group(required=True)
    mode.add_argument("--write", action="store_true", help="rewrite the generated blocks of the pages")
    mode.add_argument("--check", action="store_true", help="exit 1 if a page's block differs from its JSON")
    parser.add_argument(
        "--rerun",
        metavar="DIR",
        type=Path,
        help="first run every reproduction and write its JSON into DIR (docs/results to update them)",
    )
    args = parser.parse_args(argv)
    folder = None
    if args.rerun:
        _rerun(args.rerun)
        folder = args.rerun
    tables = load_tables(folder)
    stale = []
    for path in pages():
        text, changed = fill(path.read_text(), tables)
        stale += [f"{path.name}: {name}" for name in changed]
        if args.write and changed:
            path.write_text(text)
    if args.check and stale:
        print("generated tables differ from the reproductions' JSON:\n  " + "\n  ".join(stale), file=sys.stderr)
        return 1
    print(
        ("rewrote" if args.write else "checked") + f" {sum(len(blocks(p.read_text())) for p in pages())} tables "
        f"on {len(pages())} pages" + (f"; {len(stale)} changed" if stale else "")
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
