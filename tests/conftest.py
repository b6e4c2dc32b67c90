"""Tests never write into the checkout: numba's compiled-function cache and hypothesis's
storage go to folders in the system's temporary directory (one per checkout, so later runs
reuse them), and subprocesses of the CLI tests inherit them; pytest's own cache is off
(pyproject.toml)."""

import hashlib
import os
import tempfile
from pathlib import Path

_checkout = Path(__file__).resolve().parent.parent
_tag = hashlib.sha1(str(_checkout).encode()).hexdigest()[:12]
os.environ.setdefault("NUMBA_CACHE_DIR", os.path.join(tempfile.gettempdir(), "cnc-twin-numba-" + _tag))
# hypothesis's example database and caches (its default: .hypothesis/ in the working folder)
os.environ.setdefault("HYPOTHESIS_STORAGE_DIRECTORY", os.path.join(tempfile.gettempdir(), "cnc-twin-hypothesis-" + _tag))

from hypothesis import settings  # noqa: E402

# property-based tests: `uv run pytest --hypothesis-profile thorough` for the long run
settings.register_profile("default", max_examples=150)
settings.register_profile("thorough", max_examples=10_000)
