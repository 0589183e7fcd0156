"""The ``--json`` output of the commands: strict JSON, with ``null`` for a number that is not
finite.

Python's :func:`json.dumps` writes NaN and infinity as the bare words ``NaN`` and
``Infinity``, which are not JSON: ``jq``, JavaScript and most JSON readers refuse the whole
document. A number the tool could not compute (a bootstrap standard error without replicates,
a Pearson coefficient of a constant signal) is printed as ``null`` instead.
"""

from __future__ import annotations

import json
import math
from typing import Any

import click
import numpy as np


def strict_json_value(value: Any) -> Any:
    """``value`` with its numpy scalars and arrays made plain Python, and every float that is
    not finite made ``None``, in nested dicts, lists and tuples.

    Parameters
    ----------
    value
        What a command prints.

    Returns
    -------
    Any
        The same structure, which ``json.dumps(..., allow_nan=False)`` accepts.
    """
    if isinstance(value, dict):
        return {key: strict_json_value(item) for key, item in value.items()}
    if isinstance(value, list | tuple):
        return [strict_json_value(item) for item in value]
    if isinstance(value, np.ndarray):
        return strict_json_value(value.tolist())
    if isinstance(value, np.generic):
        return strict_json_value(value.item())
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


def echo_json(data: Any) -> None:
    """Print ``data`` as indented strict JSON (:func:`strict_json_value`).

    Parameters
    ----------
    data
        Nested dicts, lists, numbers, strings, numpy scalars and arrays.
    """
    click.echo(json.dumps(strict_json_value(data), indent=2, allow_nan=False))
