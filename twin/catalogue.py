"""The one catalogue of everything the twin knows by name: machines, controller and observer
kinds, disturbances, materials, references, inspection features, bundled scenarios and
reproducible papers, each a :class:`controllers.registries.Registry`.

``twin list`` prints its sections in order and the docs site's generated reference
(:mod:`twin.kinds_doc`) reads its registries, so the command line and the docs cannot list
different things.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from functools import cache

from controllers import CONTROLLERS, OBSERVERS
from controllers.registries import Entry, Registry
from twin.disturbances import DISTURBANCES
from twin.machines import MACHINES
from twin.machining.inspection import FEATURES
from twin.machining.materials import KIENZLE_AXIAL_RATIO, KIENZLE_RADIAL_RATIO, MATERIALS, Material
from twin.references import REFERENCES
from twin.reproductions.registry import REPRODUCTIONS
from twin.scenario import bundled_scenarios, load_scenario


def summary(entry: Entry) -> str:
    """An entry's ``twin list`` line after its name: its summary."""
    return entry.summary


def summary_and_parameters(entry: Entry) -> str:
    """An entry's summary and the names of its settings (``[params: kp, ki]``; none: the
    summary alone), the ``type`` that names the kind left out."""
    names = [name for name in getattr(entry.settings, "model_fields", ()) if name != "type"]
    return entry.summary + (f" [params: {', '.join(names)}]" if names else "")


def material_coefficients(entry: Entry[Material]) -> str:
    """A material's summary, its coefficients (linear: K_tc K_rc K_ac, K_te K_re K_ae; Kienzle:
    kc1 and mc) and their source."""
    k = entry.value.coefficients
    values = (
        f"kc1 {k.K_tc:.0f}, mc {k.mc:.3f}"
        if k.mc
        else f"{k.K_tc:g} {k.K_rc:g} {k.K_ac:g}, {k.K_te:g} {k.K_re:g} {k.K_ae:g}"
    )
    return f"{entry.summary}: {values} ({entry.value.source})"


@dataclass(frozen=True)
class Section:
    """One registry of the catalogue as ``twin list`` prints it.

    Attributes
    ----------
    key : str
        The section's name (the docs' ``<!-- kinds: KEY -->`` and ``<!-- table: KEY -->``).
    heading : str
        Its heading line in ``twin list`` (where a scenario or the command line names an entry).
    registry : Registry
        Its entries.
    width : int
        The width of the name column (characters).
    row : callable
        ``row(entry)``: the text after the name.
    """

    key: str
    heading: str
    registry: Registry
    width: int = 22
    row: Callable[[Entry], str] = summary


@cache
def scenarios() -> Registry[str]:
    """The bundled scenarios by name, sorted, each entry's summary the scenario's description and
    its value the scenario file's path (loaded once per process)."""
    registry: Registry[str] = Registry("bundled scenario")
    for name, path in sorted(bundled_scenarios().items()):
        registry.add(name, str(path), summary=load_scenario(name).description)
    return registry


#: The sections but the bundled scenarios (files, not code: :func:`scenarios`), in ``twin list``'s
#: order.
REGISTRIES: tuple[Section, ...] = (
    Section("machines", "machines (or a machine file of datasheet values, FILE.toml: examples/machines/):", MACHINES),
    Section("controllers", "controllers (type = ...):", CONTROLLERS, row=summary_and_parameters),
    Section("observers", "observers ([controller.observer] type = ...):", OBSERVERS, row=summary_and_parameters),
    Section("disturbances", "disturbances ([[disturbances]] type = ...):", DISTURBANCES),
    Section(
        "materials",
        "materials ([tool] / [[tools]] / end_milling material = ...): linear K_tc K_rc K_ac N/mm^2, K_te K_re K_ae"
        f" N/mm; Kienzle kc1 N/mm^2 and mc (kc = kc1 h^-mc), radial and axial {KIENZLE_RADIAL_RATIO:g} and"
        f" {KIENZLE_AXIAL_RATIO:g} of the tangential (our ratios, no source)",
        MATERIALS,
        width=24,
        row=material_coefficients,
    ),
    Section("references", "references ([reference] type = ...):", REFERENCES),
    Section("inspection", "inspection features ([[inspect]] type = ...):", FEATURES, row=summary_and_parameters),
    Section("reproductions", "reproductions (twin reproduce ...):", REPRODUCTIONS),
)


def sections() -> tuple[Section, ...]:
    """Every section of the catalogue in ``twin list``'s order: :data:`REGISTRIES` with the
    bundled scenarios before the reproductions."""
    return (*REGISTRIES[:-1], Section("scenarios", "scenarios:", scenarios(), width=30), REGISTRIES[-1])


def registry(key: str) -> Registry:
    """The registry of section ``key`` of :data:`REGISTRIES`.

    Raises
    ------
    KeyError
        A key that is not one of theirs.
    """
    for section in REGISTRIES:
        if section.key == key:
            return section.registry
    raise KeyError(key)


def list_lines() -> list[str]:
    """``twin list``'s lines: each section's heading, then each entry's name and row."""
    lines = []
    for section in sections():
        lines.append(section.heading)
        lines += [f"  {name:<{section.width}} {section.row(entry)}" for name, entry in section.registry.items()]
    return lines
