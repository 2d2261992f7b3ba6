"""Plain JSON values from what the package computes: numpy scalars and arrays become Python
numbers and lists, enums their names, and NaN or infinities (which JSON does not have) null."""

from __future__ import annotations

import math
from enum import Enum

import numpy as np


def jsonable(value):
    if isinstance(value, dict):
        return {str(k): jsonable(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [jsonable(v) for v in value]
    if isinstance(value, np.ndarray):
        return jsonable(value.tolist())
    if isinstance(value, Enum):
        return getattr(value, "label", value.name.lower())
    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


__all__ = ["jsonable"]
