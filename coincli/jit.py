"""The numba decorator every kernel uses, with a cache that cannot go stale.

numba's on-disk cache checks only the timestamp of the file that defines a function, not of the
files whose kernels it calls, so editing ``adaptive.py`` would leave ``kernels.integrate``
running the old code. The cache directory is therefore keyed by a hash of every kernel source.
"""

from __future__ import annotations

import hashlib
import os
from pathlib import Path

import numba
import numba.core.config

_PACKAGE = Path(__file__).resolve().parent
_KERNEL_SOURCES = ["jit.py", "params.py", "model.py", "integrators/fixed.py",
                   "integrators/adaptive.py", "integrators/kernels.py"]


def _cache_dir() -> str:
    digest = hashlib.sha256()
    for name in _KERNEL_SOURCES:
        digest.update((_PACKAGE / name).read_bytes())
    base = os.environ.get("NUMBA_CACHE_DIR") or os.path.join(
        os.environ.get("XDG_CACHE_HOME") or os.path.expanduser("~/.cache"), "coincli")
    return os.path.join(base, f"numba-{numba.__version__}-{digest.hexdigest()[:16]}")


numba.core.config.CACHE_DIR = _cache_dir()

jit = numba.njit(cache=True, fastmath=False, nogil=True)
