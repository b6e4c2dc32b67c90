"""The typed records of a run (per-line rows, warnings, inspected features) give the JSON and
the text report the untyped code gave: three runs' ``twin run --json`` and text report against
fixtures captured before the records were typed (``tests/fixtures/records/regenerate.py``),
each record's ``to_json`` against its entry there, each inspection type's report line, and the
Parquet per-line table's columns against the flattening the untyped code did."""

import json
import typing

import pytest
from records_cases import CASES, FIXTURES, json_report, run_case, text_report

from twin.machining.inspection import FEATURES, InspectSpec
from twin.records import FeatureType

_RUNS: dict = {}


def _run(name: str):
    """Case ``name``'s run, once for the module."""
    if name not in _RUNS:
        _RUNS[name] = run_case(name)
    return _RUNS[name]


@pytest.fixture(params=sorted(CASES))
def case(request):
    return request.param, _run(request.param)


def _fixture(name: str, suffix: str) -> str:
    return (FIXTURES / f"{name}.{suffix}").read_text(encoding="utf-8")


def test_the_json_and_the_text_report_are_the_untyped_codes(case):
    name, run = case
    assert json_report(run) == _fixture(name, "json")
    assert text_report(run) == _fixture(name, "txt")


def test_each_record_gives_its_json(case):
    name, run = case
    before = json.loads(_fixture(name, "json"))
    records = run.records
    assert [row.to_json() for row in records.lines] == before["lines"]
    assert [w.to_json() for w in records.machining_warnings] == before["machining_warnings"]
    assert [w.to_json() for w in records.plan_warnings] == before.get("plan_warnings", [])
    assert [f.to_json() for f in records.inspection] == before["inspection"]
    assert [w.to_json() for w in records.chatter_warnings] == before.get("chatter_warnings", [])
    assert (records.chatter and records.chatter.to_json()) == before.get("chatter")


def _report_lines(name: str) -> dict[str, str]:
    """The text report's feature lines of a case, by feature name."""
    names = [f.name for f in CASES[name][2]]
    lines = [line.strip() for line in _fixture(name, "txt").splitlines()]
    return {n: next(line for line in lines if line.startswith(f"{n} ")) for n in names}


@pytest.mark.parametrize(
    ("name", "feature", "kind"),
    [
        ("bore", "bore", "CircleMeasured"),
        ("bore", "flat", "LineMeasured"),
        ("deep_slot", "south wall", "LineMeasured"),
        ("deep_slot", "slot", "WidthMeasured"),
        ("deep_slot", "uncut", "FeatureNotFound"),
        ("deep_slot", "below", "FeatureNotFound"),
        ("bore", "one point", "FeatureNotFound"),
    ],
)
def test_each_inspection_type_prints_its_report_line(name, feature, kind):
    """The record's report line against the line the untyped code printed (measured size or
    position, deviation, form, verdict; or why not found)."""
    run = _run(name)
    found = next(f for f in run.records.inspection if f.name == feature)
    assert type(found).__name__ == kind
    assert found.report_line() == _report_lines(name)[feature]


def _untyped_columns(row: dict) -> dict:
    """A JSON row flattened as the untyped ``lines_to_parquet`` did, key by key."""
    per_axis = {f"max_tracking_error_um_{a}": v for a, v in row["max_tracking_error_um"].items()}
    check = dict(row.get("stability", {}))
    low, high = check.pop("stable_rpm", None) or (None, None)
    stability = {f"stability_{k}": v for k, v in check.items()}
    if "stability" in row:
        stability.update(stability_stable_rpm_low=low, stability_stable_rpm_high=high)
    chatter = {k if k.startswith("chatter") else f"chatter_{k}": v for k, v in row.get("chatter", {}).items()}
    plain = {k: v for k, v in row.items() if k not in ("max_tracking_error_um", "stability", "chatter")}
    return {**plain, **per_axis, **stability, **chatter}


def test_the_parquet_columns_are_the_untyped_flattening(case):
    name, run = case
    before = json.loads(_fixture(name, "json"))["lines"]
    got = [row.to_columns() for row in run.records.lines]
    assert [list(r) for r in got] == [list(_untyped_columns(r)) for r in before]  # names and order
    assert got == [_untyped_columns(r) for r in before]


def test_every_feature_type_has_one_spec_and_one_measurement():
    specs = typing.get_args(typing.get_args(InspectSpec)[0])
    literals = {typing.get_args(spec.model_fields["type"].annotation)[0] for spec in specs}
    assert literals == {t.value for t in FeatureType} == set(FEATURES)


@pytest.mark.parametrize(("listed", "total", "more"), [(25, 25, "them all"), (25, 40, "25")])
def test_a_long_list_of_warnings_prints_the_first_and_counts_the_rest(capsys, listed, total, more):
    from twin.cli import SHOWN_WARNINGS, _print_warnings
    from twin.records import MachiningWarning

    warnings = [
        MachiningWarning(line=10 + i, text=f"G1 X{i}", kind="feed_per_tooth", value=0.2, unit="mm", message="m")
        for i in range(listed)
    ]
    _print_warnings("machining warnings", warnings, total)
    out = capsys.readouterr().out.splitlines()
    assert out[0] == f"  machining warnings ({total}):"
    assert out[1] == "    line     10  m  G1 X0"
    assert len(out) == 1 + SHOWN_WARNINGS + 1
    assert out[-1] == f"    ... {total - SHOWN_WARNINGS} more (--json lists {more})"
