"""The text report of a run or a program: its worst lines, warnings, chatter and virtual part."""

from __future__ import annotations

from collections.abc import Sequence

import typer

from twin import exits
from twin.records import Inspected, LineRow, LineStability, LineWarning, RunRecords

#: Lines of a program the text summary names, worst first.
WORST_LINES = 5


def _print_worst_lines(rows: Sequence[LineRow]) -> None:
    """The program's worst lines (contour error, else tracking error) with their text."""
    if not rows:
        return
    contour = rows[0].max_contour_error_um is not None
    typer.echo(f"  worst lines ({'max contour' if contour else 'max tracking'} error, um):")
    for row in sorted(rows, key=lambda row: row.worst_error_um, reverse=True)[:WORST_LINES]:
        span = f"{row.t_start_s:.3f}-{row.t_end_s:.3f} s"
        typer.echo(f"    {row.line:>6}  {row.worst_error_um:>9.3f}  {span}  {row.text}")


#: Warnings of each kind the text summary prints (all are in --json).
SHOWN_WARNINGS = 20


def _warning_line(warning: LineWarning) -> str:
    """A warning as the text summary prints it: its line (or the run), message and the line's text."""
    where = "   run" if warning.line is None else f"line {warning.line:>6}"
    return f"{where}  {warning.message}  {warning.text}"


def _print_warnings(title: str, warnings: Sequence[LineWarning], total: int, indent: str = "  ") -> None:
    """A run's or a program's warnings of one kind under ``title``, a line each, the first
    :data:`SHOWN_WARNINGS`; ``total`` counts them all (listed or not)."""
    if not warnings:
        return
    typer.echo(f"{indent}{title} ({total}):")
    for warning in warnings[:SHOWN_WARNINGS]:
        typer.echo(f"{indent}  {_warning_line(warning)}")
    if total > SHOWN_WARNINGS:
        listed = "them all" if total == len(warnings) else str(len(warnings))
        typer.echo(f"{indent}  ... {total - SHOWN_WARNINGS} more (--json lists {listed})")


def _fail_on_warnings(title: str, warnings: Sequence[LineWarning], total: int) -> None:
    """Under ``--strict``: the first of ``warnings`` as the error line, exit 4."""
    if warnings:
        first = warnings[0]
        where = "the run" if first.line is None else f"line {first.line}"
        typer.echo(f"error: {total} {title} under --strict; the first: {where}: {first.message}", err=True)
        raise typer.Exit(exits.CHECK_FAILED)


def _print_chatter(records: RunRecords) -> None:
    """The run's chatter indicator and frequency, then the chatter warnings, a line each: by
    program line, or the run's."""
    if records.chatter is None:
        return
    typer.echo(f"  {records.chatter.report_line()}")
    warnings = records.chatter_warnings
    _print_warnings("chatter warnings", warnings, len(warnings))


def _print_chatter_check(checked: Sequence[LineStability]) -> None:
    """The program's cutting lines over their critical depth (the tool's lobes), worst first:
    ``checked`` holds each cutting line's chatter check
    (:func:`twin.machining.program_stability.line_stability`)."""
    if not checked:
        return
    over = sorted((check for check in checked if check.over_critical), key=lambda check: check.margin or 0.0)
    typer.echo(
        f"  chatter check (zero-order lobes): {len(checked)} cutting line(s), {len(over)} over their critical depth"
    )
    for check in over[:WORST_LINES]:
        typer.echo(f"    {check.text}")


def _print_part(summary: dict, inspection: Sequence[Inspected]) -> None:
    """The virtual part's wall error and each inspected feature, a line each."""
    part = summary.get("part")
    if part is None:
        return
    stats = part["surface_error_um"]
    if stats:
        typer.echo(
            f"  virtual part: wall error {stats['min']:+.3f} to {stats['max']:+.3f} µm, RMS {stats['rms']:.3f} µm"
            f" ({part['wall_points']} points at Z {', '.join(f'{z:g}' for z in part['wall_levels_mm'])} mm)"
        )
    floors = part.get("floor_error_um")
    if floors:
        typer.echo(
            f"  floors and surfaces: error {floors['min']:+.3f} to {floors['max']:+.3f} µm, RMS {floors['rms']:.3f} µm"
            f" ({floors['cells']} cells)"
        )
    if part.get("skipped_levels_mm"):
        typer.echo(
            f"  walls not read at Z {', '.join(f'{z:g}' for z in part['skipped_levels_mm'])} mm: {part['skipped_note']}"
        )
    for feature in inspection:
        typer.echo(f"    {feature.report_line()}")


def _print_summary(name: str, summary: dict) -> None:
    typer.echo(f"{name}")
    for key, value in summary.items():
        if isinstance(value, dict):
            value = "  ".join(f"{a}: {v:.3f}" for a, v in value.items())
        elif isinstance(value, float):
            value = f"{value:.3f}"
        typer.echo(f"  {key:<28} {value}")
