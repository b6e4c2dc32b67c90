"""MkDocs hooks: ``<!-- kinds: SECTION -->`` in a page becomes that registry's reference, and
``<!-- table: NAME -->`` that library's table (the materials), generated from the code
(:func:`twin.kinds_doc.kinds_markdown`, :func:`twin.kinds_doc.table_markdown`); the chatter
page's pictures are drawn by ``twin.lobes`` as the site is built (generated output is never
committed), with the settings of the commands the page shows."""

import re
import tempfile
from pathlib import Path

from mkdocs.structure.files import File

from twin import api
from twin.kinds_doc import kinds_markdown, table_markdown

MARKER = re.compile(r"<!-- kinds: ([a-z]+) -->")
TABLE = re.compile(r"<!-- table: ([a-z]+) -->")

#: The Insperger-Stepan benchmark as chatter.md's ``twin lobes slot_linear_motor`` command sets it.
BENCHMARK = {
    "disturbances.0.dynamics": {
        "modes": [{"direction": "x", "frequency_hz": 922.0, "damping_ratio": 0.011, "modal_mass_kg": 0.03993}]
    },
    "disturbances.0.coefficients": {"K_tc": 600.0, "K_rc": 200.0},
}

#: The chatter page's pictures: file name, then the ``twin.lobes`` call that draws it (the
#: program's with the zero-order method alone: its semi-discretization takes half a minute).
LOBES_PICTURES = {
    "lobes_benchmark_slot.png": lambda: api.lobes(
        "slot_linear_motor", rpm=(5000, 25000, 200), depth_max_mm=10.0, **BENCHMARK
    ),
    "lobes_benchmark_low_immersion.png": lambda: api.lobes(
        "slot_linear_motor", rpm=(5000, 25000, 200), depth_max_mm=10.0, immersion=0.05, mode="down", **BENCHMARK
    ),
    "lobes_gcode_slot_passes.png": lambda: api.lobes("gcode_slot_passes", method="zoa"),
}


def on_page_markdown(markdown, page, config, files):
    markdown = MARKER.sub(lambda m: kinds_markdown(m.group(1)), markdown)
    return TABLE.sub(lambda m: table_markdown(m.group(1)), markdown)


def on_files(files, config):
    """The chatter page's pictures, drawn into a scratch folder and added to the site."""
    with tempfile.TemporaryDirectory() as scratch:
        for name, draw in LOBES_PICTURES.items():
            path = draw().write_png(Path(scratch) / name)
            files.append(File.generated(config, f"images/{name}", content=path.read_bytes()))
    return files
