"""The paper pages' tables are generated from the reproductions' committed JSON
(``docs/results``), and that JSON is what the code computes (checked here where it is cheap, in
full by ``.ci/run``'s ``python -m twin.reproductions.tables --rerun DIR --check``)."""

import json

import pytest

from twin.reproductions.registry import REPRODUCTIONS
from twin.reproductions.tables import blocks, fill, load_tables, markdown_table, pages, results_path


def test_every_generated_table_on_the_pages_is_current():
    tables = load_tables()
    for path in pages():
        _, changed = fill(path.read_text(), tables)
        assert not changed, f"{path.name}: run `uv run python -m twin.reproductions.tables --write` ({changed})"


def test_every_table_a_reproduction_renders_is_on_a_page():
    shown = {name for path in pages() for name in blocks(path.read_text())}
    rendered = {f"{seed}.{name}" for seed, tables in load_tables().items() for name, body in tables.items() if body}
    assert rendered == shown
    assert {p.stem for p in pages()} == set(REPRODUCTIONS)


def test_markdown_table_escapes_pipes():
    assert markdown_table(["a", "b"], [["|x|", 1]]) == "| a | b |\n|---|---|\n| \\|x\\| | 1 |\n"


@pytest.mark.parametrize("seed", sorted(REPRODUCTIONS))
def test_committed_results_were_written_with_the_default_settings(seed):
    """The JSON behind the pages is `twin reproduce SEED --json` with its defaults (the twin on)."""
    settings = json.loads(results_path(seed).read_text())["settings"]
    assert settings.get("twin", True) is True
    if "samples" in settings:
        assert settings["samples"] == 1000
        assert settings["seed"] == 0
    if "mc_samples" in settings:
        assert (settings["mc_samples"], settings["twin_random"], settings["seed"]) == (1000, 20, 0)
