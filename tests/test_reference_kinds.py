"""Reference kinds register themselves: the scenario schema, `twin list` and the runs read the
registry, so a new kind is one new module in twin/references/ (checked on a copy of the
package with one module added)."""

import json
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from twin.references import REFERENCES
from twin.scenario import Scenario

ROOT = Path(__file__).resolve().parent.parent

HOLD = '''"""A test reference kind: every axis held at one position."""

from dataclasses import dataclass
from typing import Literal

import numpy as np

from twin.references.kinds import ReferenceSpecBase, per_axis, register


@dataclass
class Hold:
    position_m: float
    n_axes: int

    def sample(self, t):
        s = np.zeros((np.size(t), 3))
        s[:, 0] = self.position_m
        return per_axis(s, self.n_axes, None)


class HoldRef(ReferenceSpecBase):
    """hold: every axis at position_m from t = 0."""

    type: Literal["hold"]
    position_m: float


register("hold", HoldRef, lambda spec, ctx: Hold(spec.position_m, len(ctx.axis_names)))
'''

SCENARIO = """
machine = "cncmt"
duration_s = 0.5
[controller]
type = "yadav2020_imc"
[reference]
type = "hold"
position_m = 0.001
"""


def test_the_schema_is_the_registry():
    tags = set(Scenario.model_json_schema()["properties"]["reference"]["discriminator"]["mapping"])
    assert tags == set(REFERENCES) == {"step", "ramp", "sines", "circle", "square", "polyline", "gcode"}


@pytest.mark.slow  # a copy of the tree compiles every kernel afresh: about 15 s
def test_a_new_kind_is_one_module(tmp_path):
    for package in ("twin", "controllers", "mjcf"):
        shutil.copytree(ROOT / package, tmp_path / package, ignore=shutil.ignore_patterns("__pycache__"))
    (tmp_path / "twin" / "references" / "hold.py").write_text(HOLD)
    (tmp_path / "hold.toml").write_text(SCENARIO)
    env = {"PYTHONPATH": str(tmp_path), "PATH": "/usr/bin:/bin"}
    listing = subprocess.run(
        [sys.executable, "-m", "twin.cli", "list"], capture_output=True, text=True, env=env, cwd=tmp_path, timeout=300
    )
    assert listing.returncode == 0, listing.stderr
    assert "hold                   every axis at position_m from t = 0." in listing.stdout
    run = subprocess.run(
        [sys.executable, "-m", "twin.cli", "run", "hold.toml", "--json"],
        capture_output=True,
        text=True,
        env=env,
        cwd=tmp_path,
        timeout=300,
    )
    assert run.returncode == 0, run.stderr
    out = json.loads(run.stdout)
    # a 1 mm step at t = 0: the largest error is the step itself, at the first tick
    assert out["max_tracking_error_um"]["x"] == 1000.0
