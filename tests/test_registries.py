"""Kinds that register themselves: every reference, disturbance, controller, observer, machine,
material, inspection feature and reproduction is declared once, in a registry of one type
(:mod:`controllers.registries`), and the scenario schema, ``twin list``, the docs and the runs all read the
same registries through one catalogue (:mod:`twin.catalogue`)."""

from pathlib import Path

import pytest
from pydantic import Field
from typer.testing import CliRunner

from controllers import CONTROLLERS, OBSERVERS, make_controller
from controllers.design.pid import pid_tf
from controllers.kinds.generic import error_feedback_each_axis
from controllers.registries import Entry, Registry, UnknownName
from controllers.registry import ParameterError, Params, controller_kind
from twin import api
from twin.catalogue import REGISTRIES, registry, sections
from twin.cli import app
from twin.disturbances import DISTURBANCES
from twin.errors import TwinInputError
from twin.kinds_doc import SECTIONS, TABLES, kinds_markdown, table_markdown
from twin.machines import MACHINES, get_machine
from twin.machining.inspection import FEATURES
from twin.machining.materials import MATERIALS
from twin.references import REFERENCES
from twin.reproductions.base import Reproduction
from twin.reproductions.registry import REPRODUCTIONS
from twin.scenario import scenario_from_dict


def test_the_catalogue_holds_every_registry_of_one_type():
    registries = {section.key: section.registry for section in REGISTRIES}
    assert registries == {
        "machines": MACHINES,
        "controllers": CONTROLLERS,
        "observers": OBSERVERS,
        "disturbances": DISTURBANCES,
        "materials": MATERIALS,
        "references": REFERENCES,
        "inspection": FEATURES,
        "reproductions": REPRODUCTIONS,
    }
    for key, kinds in registries.items():
        assert isinstance(kinds, Registry), key
        assert registry(key) is kinds
        assert len(kinds) >= 3, key
        for name, entry in kinds.items():
            assert isinstance(entry, Entry) and entry.name == name, (key, name)
            assert entry.summary and "\n" not in entry.summary, (key, name)
    *before, last = registries
    assert [s.key for s in sections()] == [*before, "scenarios", last]
    with pytest.raises(KeyError):
        registry("scenarios")


def test_the_docs_reference_lists_every_kind_and_parameter_of_the_catalogue():
    """The generated pages match the catalogue: each section's every entry by name with its
    summary, and every parameter of its settings, a row of its table."""
    assert set(SECTIONS) | set(TABLES) == {section.key for section in REGISTRIES}
    for section in SECTIONS:
        text = kinds_markdown(section)
        for name, entry in registry(section).items():
            assert f"`{name}`" in text, (section, name)
            assert entry.summary.replace("|", "\\|") in text, (section, name)
            for field in getattr(entry.settings, "model_fields", {}):
                if field != "type":
                    assert f"| `{field}` |" in text, (section, name, field)
    assert "| `tf_s` | `0.0` | ≥ 0 | derivative filter time constant, s |" in kinds_markdown("controllers")
    assert "| `diameter_mm` | required | ≤ 10000, > 0 | nominal diameter (mm) |" in kinds_markdown("inspection")
    materials = table_markdown("materials")
    for name, entry in MATERIALS.items():
        assert f"| `{name}`" in materials and entry.value.source in materials, name
    with pytest.raises(KeyError):
        kinds_markdown("gcode")
    with pytest.raises(KeyError):
        kinds_markdown("materials")


def test_twin_list_shows_every_entry_of_the_catalogue_with_its_docs_line():
    out = CliRunner().invoke(app, ["list"]).output.splitlines()
    for section in sections():
        assert section.heading in out, section.key
        for name, entry in section.registry.items():
            assert any(line.startswith(f"  {name:<{section.width}} {entry.summary}") for line in out), name
    pid = "kp + ki/s + kd s/(tf_s s + 1) on the error of each axis. [params: kp, ki, kd, tf_s]"
    assert f"  {'pid':<22} {pid}" in out
    assert "  circle                 A bore or boss. [params: name, z_mm, tolerance_um, center_mm, diameter_mm]" in out
    assert out.index("scenarios:") < out.index("reproductions (twin reproduce ...):")


def test_an_unknown_name_is_one_line_naming_the_field_the_value_and_the_known_names():
    with pytest.raises(UnknownName) as unknown:
        FEATURES.lookup("cone", field="inspect.0.type")
    assert str(unknown.value) == "inspect.0.type = 'cone': unknown inspection feature (known: circle, line, width)"
    with pytest.raises(TwinInputError) as err:
        get_machine("lathe")
    assert (err.value.field, err.value.value) == ("machine", "lathe")
    assert err.value.reason == f"unknown machine (known: {', '.join(MACHINES)}; or a machine file, FILE.toml)"
    scenario = {"machine": "cncmt", "duration_s": 0.1, "reference": {"type": "step", "amplitude_m": 0.001}}
    for table, field, what, known in (
        ({"type": "pi_d"}, "controller.type", "controller", CONTROLLERS),
        ({"type": "pid", "observer": {"type": "kalman"}}, "controller.observer.type", "observer", OBSERVERS),
    ):
        with pytest.raises(TwinInputError) as err:
            api.run(scenario_from_dict({**scenario, "controller": table}))
        assert err.value.field == field
        assert err.value.reason == f"unknown {what} (known: {', '.join(known)})"
    with pytest.raises(TwinInputError, match=r"tools.0.material = 'wood': Input should be 'aluminium_7075_t6'"):
        scenario_from_dict({**scenario, "tools": [{"number": 1, "diameter_mm": 6.0, "material": "wood"}]})


def test_a_name_registered_twice_is_refused():
    kinds: Registry[int] = Registry("test kind")
    kinds.add("one", 1, summary="The first\n  of them.")
    assert kinds["one"] == Entry("one", "The first of them.", None, 1)
    for name in ("one", ""):
        with pytest.raises(ValueError, match="registered twice"):
            kinds.add(name, 2, summary="again")


class GainParams(Params):
    gain_V_per_m: float = Field(gt=0.0, description="V/m")


def test_a_new_controller_kind_is_one_registration(monkeypatch):
    """A kind registered from outside the package runs from a scenario, with its parameters
    checked by its own model."""

    def build(p, ctx):
        """A P controller (test kind)."""
        return error_feedback_each_axis(pid_tf(p.gain_V_per_m), ctx)

    monkeypatch.setitem(CONTROLLERS, "test_p", Entry("test_p", "A P controller (test kind).", GainParams, build))
    scenario = {
        "machine": "cncmt",
        "duration_s": 0.2,
        "control_period_s": 1e-3,
        "controller": {"type": "test_p", "params": {"gain_V_per_m": 30.0}},
        "reference": {"type": "step", "amplitude_m": 0.001},
    }
    p_run = api.run(scenario_from_dict(scenario))
    pid_run = api.run(scenario_from_dict({**scenario, "controller": {"type": "pid", "params": {"kp": 30.0}}}))
    assert p_run.summary["max_tracking_error_um"] == pid_run.summary["max_tracking_error_um"]
    assert p_run.summary["max_tracking_error_um"]["x"] > 0
    with pytest.raises(TwinInputError, match=r"controller.params.gain_V_per_m = -1.0: Input should be greater than 0"):
        api.run(scenario_from_dict({**scenario, "controller": {"type": "test_p", "params": {"gain_V_per_m": -1.0}}}))


def test_parameter_errors_name_the_parameter():
    with pytest.raises(ParameterError) as err:
        make_controller("pid", 1e-3, {"gain": 1.0})
    assert (err.value.field, err.value.value) == ("gain", 1.0)
    assert err.value.reason == "not a parameter of pid (its parameters: kp, ki, kd, tf_s)"
    with pytest.raises(ParameterError) as err:
        make_controller("sabau2022", 1e-3, {"velocity_ff": "yes"}, axes=("x", "y"))
    assert err.value.field == "velocity_ff"
    assert "valid boolean" in err.value.reason
    with pytest.raises(ParameterError) as err:
        make_controller("linear", 1e-3, {"inputs": ["error", 3]})
    assert err.value.field == "inputs.1"


def test_a_kind_registered_twice_is_refused():
    with pytest.raises(ValueError, match="registered twice"):
        controller_kind("pid")(lambda p, ctx: None)


def test_every_reproduction_offers_the_whole_interface(tmp_path: Path):
    for name, entry in REPRODUCTIONS.items():
        paper = entry.value
        assert isinstance(paper, Reproduction)
        assert paper.name == name
        report = paper.report()
        for entry in ("run", "format_report", "markdown_tables", "write_plots", "twin_runs"):
            assert callable(getattr(report, entry)), (name, entry)
    # the shared verdict reads the twin-vs-TF mismatches every report computes
    assert REPRODUCTIONS["anang2017"].value.failed({"twin_vs_tf_mismatches": ["x"]})
    assert not REPRODUCTIONS["anang2017"].value.failed({"twin_vs_tf_mismatches": []})
    # the certificates hook: Choi 1999's mu bound for its own controllers, nothing elsewhere
    assert REPRODUCTIONS["anang2017"].value.certificates("googol_xy", "anang2017_pid", {"m"}, []) == []


def test_the_reproductions_and_the_kinds_keep_the_order_of_the_source_texts():
    """Whatever a process imported first, the papers come in the order of shared/seeds (the
    command line's lists and error lines do not depend on which test ran before)."""
    from controllers.papers import PAPERS
    from controllers.registry import CONTROLLERS

    assert tuple(REPRODUCTIONS) == PAPERS
    papers_of_kinds = [name.split("_")[0] for name in CONTROLLERS if name.split("_")[0] in PAPERS]
    assert list(dict.fromkeys(papers_of_kinds)) == list(PAPERS)


def test_each_machine_readme_states_its_motion_limits():
    from twin.kinds_doc import motion_limits_table

    root = Path(__file__).resolve().parent.parent
    for name, entry in MACHINES.items():
        readme = (root / "mjcf" / name / "README.md").read_text()
        assert motion_limits_table(entry.value) in readme, name
