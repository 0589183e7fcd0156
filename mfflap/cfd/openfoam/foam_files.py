"""OpenFOAM dictionaries and field files through foamlib's parser, imported when first
needed: foamlib takes about half a second to import, and most commands never edit a case.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any


def foam_file(path: str | Path) -> Any:
    """A :class:`foamlib.FoamFile` of ``path`` (read and written on access; ``with`` it to
    write several changes at once).

    Examples
    --------
    >>> import tempfile
    >>> from pathlib import Path
    >>> path = Path(tempfile.mkdtemp()) / "controlDict"
    >>> _ = path.write_text("maxCo 4;\\n")
    >>> control = foam_file(path)
    >>> control["maxCo"] = 2.0
    >>> foam_file(path)["maxCo"]
    2.0
    """
    # foamlib takes about half a second to load: only case edits need it
    from foamlib import FoamFile

    return FoamFile(path)


def decode_error() -> type[Exception]:
    """foamlib's error for a file it cannot parse (for ``except decode_error():``)."""
    # foamlib takes about half a second to load: only case edits need it
    from foamlib import FoamFileDecodeError

    return FoamFileDecodeError
