"""Kinds that register themselves: every reference, disturbance, controller, observer, machine
and reproduction is declared once, and the scenario schema, ``twin list``, the docs and the
runs all read the same registries."""

from pathlib import Path

import pytest
from pydantic import Field
from typer.testing import CliRunner

from controllers import CONTROLLERS, OBSERVERS, make_controller
from controllers.design.pid import pid_tf
from controllers.kinds.generic import error_feedback_each_axis
from controllers.registry import ControllerKind, ParameterError, Params, controller_kind
from twin import api
from twin.cli import app
from twin.disturbances import DISTURBANCES
from twin.errors import TwinInputError
from twin.kinds_doc import SECTIONS, kinds_markdown
from twin.machines import MACHINES
from twin.references import REFERENCES
from twin.reproductions.base import Reproduction
from twin.reproductions.registry import REPRODUCTIONS
from twin.scenario import scenario_from_dict

REGISTRIES = {
    "references": REFERENCES,
    "disturbances": DISTURBANCES,
    "controllers": CONTROLLERS,
    "observers": OBSERVERS,
    "machines": MACHINES,
    "reproductions": REPRODUCTIONS,
}


def test_the_docs_reference_lists_every_kind_and_parameter_of_every_registry():
    assert set(SECTIONS) == set(REGISTRIES)
    for section, registry in REGISTRIES.items():
        text = kinds_markdown(section)
        for name, kind in registry.items():
            assert f"`{name}`" in text, (section, name)
            params = getattr(kind, "params", None) or getattr(kind, "spec", None)
            for field in getattr(params, "model_fields", {}):
                if field != "type":
                    assert f"| `{field}` |" in text, (section, name, field)
    assert "| `tf_s` | `0.0` | ≥ 0 | derivative filter time constant, s |" in kinds_markdown("controllers")
    with pytest.raises(KeyError):
        kinds_markdown("gcode")


def test_twin_list_shows_every_registered_kind_with_its_docs_line():
    out = CliRunner().invoke(app, ["list"]).output
    for registry in REGISTRIES.values():
        for name, kind in registry.items():
            doc = getattr(kind, "doc", None) or kind.summary
            assert f"{name:<22} {doc.removeprefix(name + ': ')}" in out, name


class GainParams(Params):
    gain_V_per_m: float = Field(gt=0.0, description="V/m")


def test_a_new_controller_kind_is_one_registration(monkeypatch):
    """A kind registered from outside the package runs from a scenario, with its parameters
    checked by its own model."""

    def build(p, ctx):
        """A P controller (test kind)."""
        return error_feedback_each_axis(pid_tf(p.gain_V_per_m), ctx)

    monkeypatch.setitem(CONTROLLERS, "test_p", ControllerKind("test_p", GainParams, build))
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
    for name, paper in REPRODUCTIONS.items():
        assert isinstance(paper, Reproduction)
        assert paper.name == name
        report = paper.report()
        for entry in ("run", "format_report", "markdown_tables", "write_plots", "twin_runs"):
            assert callable(getattr(report, entry)), (name, entry)
    # the shared verdict reads the twin-vs-TF mismatches every report computes
    assert REPRODUCTIONS["anang2017"].failed({"twin_vs_tf_mismatches": ["x"]})
    assert not REPRODUCTIONS["anang2017"].failed({"twin_vs_tf_mismatches": []})
    # the certificates hook: Choi 1999's mu bound for its own controllers, nothing elsewhere
    assert REPRODUCTIONS["anang2017"].certificates("googol_xy", "anang2017_pid", {"m"}, []) == []


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
    for name, machine in MACHINES.items():
        readme = (root / "mjcf" / name / "README.md").read_text()
        assert motion_limits_table(machine) in readme, name
