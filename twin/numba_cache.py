"""Numba's on-disk cache, keyed on the source of every compiled kernel.

numba invalidates a cached function when its own file changes, not when a kernel it inlines
from another file does: the compiled loop (``twin/sim/loop.py``) inlines ``sense`` and
``drive_command`` (``twin/sim/drive.py``), ``run_blocks`` (``controllers/kernels.py``) and the
force kernels (``twin/machining/cutting.py``), and the transfer-function loop
(``twin/sim/tf_loop.py``) the same.  So every module that defines cached kernels calls
:func:`configure` before its first ``@njit(cache=True)``: the cache then lives in a folder named by
a hash of all of :data:`KERNEL_FILES`, and an edit to any of them starts a fresh folder (tested in
``tests/test_numba_cache.py``).

The folder is ``$NUMBA_CACHE_DIR/kernels-<hash>`` when ``NUMBA_CACHE_DIR`` is set (the tests set it
outside the checkout), else ``<user cache>/cnc-feed-drive-twin/numba/kernels-<hash>``, where the
user cache is ``$XDG_CACHE_HOME`` or ``~/.cache`` (the system's temporary folder if neither can be
written).
"""

from __future__ import annotations

import hashlib
import os
import tempfile
from functools import lru_cache
from pathlib import Path

import numba

_ROOT = Path(__file__).resolve().parent.parent
#: Every file that defines a compiled kernel another file's compiled function may inline.
KERNEL_FILES = (
    "controllers/kernels.py",
    "twin/sim/drive.py",
    "twin/sim/loop.py",
    "twin/sim/tf_loop.py",
    "twin/machining/cutting.py",
    "twin/metrics.py",
)


@lru_cache(maxsize=1)
def cache_dir() -> Path:
    """The keyed cache folder (created)."""
    digest = hashlib.sha256()
    for name in KERNEL_FILES:
        digest.update(name.encode())
        digest.update((_ROOT / name).read_bytes())
    key = f"kernels-{digest.hexdigest()[:16]}"
    base = os.environ.get("NUMBA_CACHE_DIR")
    candidates = [Path(base)] if base else []
    home = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    candidates += [
        Path(home) / "cnc-feed-drive-twin" / "numba",
        Path(tempfile.gettempdir()) / "cnc-feed-drive-twin-numba",
    ]
    for folder in candidates:
        try:
            (folder / key).mkdir(parents=True, exist_ok=True)
        except OSError:
            continue
        if os.access(folder / key, os.W_OK):
            return folder / key
    raise OSError(f"no writable folder for numba's cache among {[str(c) for c in candidates]}")


def configure() -> Path:
    """Point numba's cache at :func:`cache_dir` (before the calling module's kernels are defined)."""
    path = cache_dir()
    numba.config.CACHE_DIR = str(path)  # type: ignore[attr-defined]  # set from the environment at import
    return path
