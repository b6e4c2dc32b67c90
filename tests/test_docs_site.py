"""The docs site builds with every warning an error (a broken link, a missing snippet, a
docstring the API reference cannot read), from the repository root as CI builds it."""

import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def test_the_docs_site_builds_strict(tmp_path):
    mkdocs = Path(sys.executable).parent / "mkdocs"
    env = {**os.environ, "NO_MKDOCS_2_WARNING": "1"}
    r = subprocess.run(
        [
            str(mkdocs),
            "build",
            "--strict",
            "-f",
            str(ROOT / "docs" / "mkdocs.yml"),
            "--site-dir",
            str(tmp_path / "site"),
        ],
        capture_output=True,
        text=True,
        cwd=ROOT,
        env=env,
        timeout=300,
    )
    assert r.returncode == 0, r.stderr[-3000:]
    page = (tmp_path / "site" / "machines" / "googol_xy" / "index.html").read_text()
    assert "Googol Tech XY ball-screw table" in page  # the machine's README, included from mjcf/
    assert "twin.api.run" in (tmp_path / "site" / "api" / "index.html").read_text()  # the API reference
    kinds = (tmp_path / "site" / "kinds" / "index.html").read_text()  # generated from the registries
    assert "choi1999_mimo" in kinds
    assert "derivative filter time constant, s" in kinds
    assert "<!-- kinds" not in kinds
