"""Where numba keeps the machine code it compiles for mfflap's kernels.

numba writes the cache of a ``cache=True`` function beside its source by default, inside the
installed package. pip does not know these files: uninstalling the package leaves its folder
behind with only the caches in it, and that folder then shadows a later (editable) install of
mfflap. mfflap therefore points numba's cache at a folder of the user's cache directory
(``$XDG_CACHE_HOME/mfflap/numba``, else ``~/.cache/mfflap/numba``) unless ``NUMBA_CACHE_DIR``
already names one. Importing this module does it; ``mfflap/__init__.py`` imports it before
anything that compiles a kernel.

Examples
--------
>>> from pathlib import Path
>>> import mfflap
>>> Path(mfflap.__file__).parent in Path(numba_cache_folder()).parents
False
"""

from __future__ import annotations

import os
import sys
from pathlib import Path


def numba_cache_folder() -> str:
    """The folder numba caches mfflap's compiled kernels in (``NUMBA_CACHE_DIR``)."""
    chosen = os.environ.get("NUMBA_CACHE_DIR")
    if chosen:
        return chosen
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return str(Path(base) / "mfflap" / "numba")


def keep_compiled_caches_out_of_the_package() -> None:
    """Set numba's cache folder to :func:`numba_cache_folder`, for this process and the
    processes it starts (dask workers), whether or not numba is imported yet."""
    folder = numba_cache_folder()
    os.environ["NUMBA_CACHE_DIR"] = folder
    numba = sys.modules.get("numba")
    if numba is not None:  # imported before mfflap: its configuration is read already
        numba.config.CACHE_DIR = folder


keep_compiled_caches_out_of_the_package()
