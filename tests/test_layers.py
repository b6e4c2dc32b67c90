"""The layer rules, as import-linter contracts in pyproject.toml: controllers never import the
twin or MuJoCo; the physics never imports the reproductions, sweeps, API or CLI; the sweeps reach
the reproductions only through their registry; only the CLI imports the CLI."""

import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def test_import_contracts_are_kept():
    lint = Path(sys.executable).parent / "lint-imports"
    r = subprocess.run(
        [str(lint), "--no-cache", "--config", str(ROOT / "pyproject.toml")],
        capture_output=True,
        text=True,
        cwd=ROOT,
        timeout=120,
    )
    assert r.returncode == 0, r.stdout[-3000:]
    assert "Contracts: 4 kept, 0 broken." in r.stdout
