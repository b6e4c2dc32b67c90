"""A kernel edited in one file is picked up by the compiled loops that inline it from another
(numba alone would reuse the stale compiled loop: it checks only the loop's own file)."""

import json
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
SATURATION = "ua[a] = min(max(u[a] + u_dist[row, a], -limit), limit)"


def _run(tree: Path, cache: Path) -> dict:
    env = {"PYTHONPATH": str(tree), "PATH": "/usr/bin:/bin", "NUMBA_CACHE_DIR": str(cache)}
    r = subprocess.run(
        [sys.executable, "-m", "twin.cli", "run", "choi1999_pid_air_cut", "--json", "--set", "duration_s=0.05"],
        capture_output=True,
        text=True,
        env=env,
        cwd=tree,
        timeout=600,
    )
    assert r.returncode == 0, r.stderr
    return json.loads(r.stdout)


@pytest.mark.slow
def test_an_edited_kernel_is_recompiled_into_the_loop(tmp_path):
    tree, cache = tmp_path / "tree", tmp_path / "cache"
    for package in ("twin", "controllers", "mjcf"):
        shutil.copytree(ROOT / package, tree / package, ignore=shutil.ignore_patterns("__pycache__"))
    before = _run(tree, cache)
    assert before["loop"] == "compiled"
    drive = tree / "twin" / "sim" / "drive.py"
    text = drive.read_text()
    assert SATURATION in text
    # the drive applies half the command: only drive.py changes, not loop.py that inlines it
    drive.write_text(text.replace(SATURATION, "ua[a] = 0.5 * min(max(u[a] + u_dist[row, a], -limit), limit)"))
    after = _run(tree, cache)
    assert after["loop"] == "compiled"
    assert after["max_tracking_error_um"] != before["max_tracking_error_um"]
    assert len(list(cache.glob("kernels-*"))) == 2  # one keyed folder per version of the kernels
