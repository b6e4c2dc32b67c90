"""The docs site's reference of every registered kind, generated from the registries of the
catalogue (:mod:`twin.catalogue`, which ``twin list`` prints; ``docs/hooks.py`` puts it where a
page says ``<!-- kinds: NAME -->``), so the docs cannot drift from the code: each kind's docs
line, and its parameters with defaults, limits and units; and the tables of other libraries
(``<!-- table: NAME -->``: the materials)."""

from __future__ import annotations

from pydantic import BaseModel

from controllers.registries import Registry
from twin.catalogue import registry

#: What a ``<!-- kinds: NAME -->`` marker may name: a section of the catalogue.
SECTIONS = ("references", "disturbances", "controllers", "observers", "inspection", "machines", "reproductions")

_LIMITS = {"ge": "≥", "gt": ">", "le": "≤", "lt": "<"}


def _limits(info) -> str:
    """A field's bounds, e.g. ``> 0, ≤ 2``."""
    out = []
    for item in info.metadata:
        for attr, sign in _LIMITS.items():
            bound = getattr(item, attr, None)
            if bound is not None:
                out.append(f"{sign} {bound:g}")
    return ", ".join(out)


def _cell(text: str) -> str:
    return text.replace("|", "\\|").replace("\n", " ")


def parameter_table(model: type[BaseModel] | None, skip: tuple[str, ...] = ("type",)) -> str:
    """A markdown table of a pydantic model's fields (None: none): name, default, limits,
    description."""
    rows = ["| parameter | default | limits | what (unit) |", "|---|---|---|---|"]
    for name, info in (model.model_fields if model else {}).items():
        if name in skip:
            continue
        default = "required" if info.is_required() else f"`{info.get_default(call_default_factory=True)!r}`"
        rows.append(f"| `{name}` | {default} | {_limits(info)} | {_cell(info.description or '')} |")
    return "\n".join(rows) if len(rows) > 2 else "No parameters."


def _kinds(kinds: Registry) -> str:
    """Each kind's heading, summary and parameter table."""
    parts = []
    for name, kind in kinds.items():
        parts += [f"### `{name}`", "", _cell(kind.summary), "", parameter_table(kind.settings), ""]
    return "\n".join(parts)


def motion_limits_table(machine) -> str:
    """A machine's motion limits (the G-code interpolator's) as the markdown table its README
    holds (``tests/test_registries.py`` checks that it does)."""
    from twin.machines.base import SPINDLE_HEAD_Z

    limits = {**machine.motion_limits, "z": machine.motion_limits.get("z", SPINDLE_HEAD_Z)}
    rows = ["| axis | velocity (m/s) | acceleration (m/s²) | jerk (m/s³) | source |", "|---|---|---|---|---|"]
    for axis in [a.name for a in machine.axes] + ["z"]:
        lim = limits[axis]
        rows.append(
            f"| {axis} | {lim.velocity_m_per_s:.4g} | {lim.acceleration_m_per_s2:.4g} | {lim.jerk_m_per_s3:.4g} | "
            f"{_cell(lim.source)} |"
        )
    return "\n".join(rows)


def _machines(machines: Registry) -> str:
    """Each machine's heading, summary, parameters and motion limits."""
    parts = []
    for name, entry in machines.items():
        machine = entry.value
        rows = ["| symbol | nominal | unit | what (source) |", "|---|---|---|---|"]
        rows += [f"| `{s}` | {p.value:g} | {p.unit} | {_cell(p.description)} |" for s, p in machine.parameters.items()]
        limits = motion_limits_table(machine)
        parts += [f"### `{name}`", "", entry.summary, "", *rows, "", "Motion limits:", "", limits, ""]
    return "\n".join(parts)


#: What each ``<!-- table: NAME -->`` marker expands to (:func:`table_markdown`).
TABLES = ("materials",)


def materials_table() -> str:
    """The materials library (:data:`twin.machining.materials.MATERIALS`, the catalogue's
    ``materials``) as a markdown table: each entry's model, alloy, cutter, lubrication,
    coefficients, Kienzle exponent, fit residual and source."""
    from twin.machining.materials import DEFAULT_MATERIAL

    rows = [
        "| name | model | alloy | cutter | lubrication | K_tc or kc1 | K_rc | K_ac | K_te | K_re | K_ae | mc "
        "| fit residual | source |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for name, entry in registry("materials").items():
        m = entry.value
        k = m.coefficients
        default = " (default)" if name == DEFAULT_MATERIAL else ""
        values = " | ".join(f"{v:g}" for v in k.as_array())
        residual = f"{m.fit.max_relative_residual:.1%}" if m.fit else ""
        described = " | ".join(_cell(text) for text in (m.model, m.alloy, m.cutter, m.lubrication))
        rows.append(f"| `{name}`{default} | {described} | {values} | {residual} | {_cell(m.source)} |")
    return "\n".join(rows) + "\n"


def table_markdown(name: str) -> str:
    """The markdown of one table of :data:`TABLES`, from the code.

    Raises
    ------
    KeyError
        A name that is not one of :data:`TABLES`.
    """
    if name == "materials":
        return materials_table()
    raise KeyError(name)


def kinds_markdown(section: str) -> str:
    """The markdown of one section of :data:`SECTIONS`, from its registry in the catalogue.

    Raises
    ------
    KeyError
        A section that is not one of :data:`SECTIONS`.
    """
    if section not in SECTIONS:
        raise KeyError(section)
    entries = registry(section)
    if section == "machines":
        return _machines(entries)
    if section == "reproductions":
        return "\n".join(f"- `{name}`: {paper.summary}" for name, paper in entries.items()) + "\n"
    return _kinds(entries)
