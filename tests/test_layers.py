"""The layer rules, as import-linter contracts in pyproject.toml: controllers never import the
twin or MuJoCo; the registry type (``controllers.registries``) imports nothing of the twin or the controllers;
each layer of the twin imports only the layers below it (from the errors up to the
command line; a function's own imports count too); no import cycle among the modules of any
package of the twin (its whole tree); the sweeps reach the reproductions only through their
registry."""

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
    assert "Contracts: 5 kept, 0 broken." in r.stdout
    assert "the one registry type imports no other module KEPT" in r.stdout
    assert "no import cycle among the modules (or subpackages) of any package of the twin KEPT" in r.stdout
