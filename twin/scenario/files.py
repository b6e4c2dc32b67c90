"""Scenario files: the bundled ones by name, reading a TOML file (its relative paths made
relative to it), validating it, with settings applied."""

from __future__ import annotations

from importlib import resources
from pathlib import Path
from typing import Any

from pydantic import ValidationError

from twin.errors import input_file
from twin.machines import is_machine_file
from twin.references import REFERENCES
from twin.scenario.schema import Scenario
from twin.settings import set_fields
from twin.spec import read_toml, validation_error


def bundled_scenarios() -> dict[str, Path]:
    """Bundled scenario files by name (file stem)."""
    folder = resources.files("twin") / "scenarios"
    return {Path(p.name).stem: Path(str(p)) for p in folder.iterdir() if p.name.endswith(".toml")}


def read_scenario_data(source: str | Path) -> dict:
    """A scenario file or bundled scenario as the dict its TOML holds (not yet validated).

    Raises
    ------
    TwinInputError
        Missing file, malformed TOML, or a file that is not UTF-8 text.
    """
    bundled = bundled_scenarios()
    missing = f"no such file or bundled scenario (bundled: {', '.join(sorted(bundled))})"
    path = bundled[str(source)] if str(source) in bundled else input_file(source, "scenario", missing)
    return _relative_to(read_toml(path, "scenario file"), path.parent)


def _relative_to(data: dict, folder: Path) -> dict:
    """``data`` with its file fields (a machine file, the reference's ``relative_paths``, a tool's
    ``dynamics.frf_file``) made relative to the scenario file's ``folder`` where they are
    relative paths."""
    machine = data.get("machine")
    if isinstance(machine, str) and is_machine_file(machine) and not Path(machine).is_absolute():
        data["machine"] = str(folder / machine)
    reference = data.get("reference")
    if isinstance(reference, dict) and isinstance(reference.get("type"), str) and reference["type"] in REFERENCES:
        for key in getattr(REFERENCES[reference["type"]].settings, "relative_paths", ()):
            value = reference.get(key)
            if isinstance(value, str) and not Path(value).is_absolute():
                reference[key] = str(folder / value)
    tools = [data.get("tool"), *_dicts(data.get("tools")), *_dicts(data.get("disturbances"))]
    for tool in tools:
        dynamics = tool.get("dynamics") if isinstance(tool, dict) else None
        if isinstance(dynamics, dict):
            frf_file = dynamics.get("frf_file")
            if isinstance(frf_file, str) and not Path(frf_file).is_absolute():
                dynamics["frf_file"] = str(folder / frf_file)
    return data


def _dicts(value) -> list:
    """``value`` if it is a list (of tables), else no tables."""
    return value if isinstance(value, list) else []


def load_scenario(source: str | Path, settings: dict[str, Any] | None = None, label: str = "") -> Scenario:
    """Read and validate a scenario from a file path or a bundled scenario name: the one loader
    of the command line and the API.

    ``settings`` (dotted paths to values, :func:`twin.settings.set_fields`) change fields before
    validation; an error in one names its path after ``label`` (``"--set "`` on the command line).

    Raises
    ------
    TwinInputError
        Missing file, malformed TOML, a setting that leads nowhere or an invalid field (named in
        the message).
    """
    return scenario_from_dict(set_fields(read_scenario_data(source), settings or {}, label))


def scenario_from_dict(data: dict) -> Scenario:
    """Validate a scenario given as a dict (as parsed from TOML)."""
    try:
        return Scenario.model_validate(data)
    except ValidationError as exc:
        raise validation_error(exc, data) from None
