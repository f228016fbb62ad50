"""Integer arguments checked against the C++ types they become.

pybind11 refuses a Python int past its C++ parameter's range with a generic
TypeError ("incompatible function arguments") that names neither the
argument nor the cause; these checks raise OverflowError naming both first.
"""
from __future__ import annotations

from typing import Any

INT32 = (-2 ** 31, 2 ** 31 - 1)
INT64 = (-2 ** 63, 2 ** 63 - 1)


def _shown(v: int) -> str:
    # str() of an int past 4300 digits raises ValueError (Python 3.11)
    return str(v) if v.bit_length() <= 256 else f"a {v.bit_length()}-bit integer"


def int_arg(value: Any, name: str, bounds=INT64) -> int:
    """int(value), OverflowError naming `name` outside `bounds` (inclusive)."""
    v = int(value)
    lo, hi = bounds
    if not lo <= v <= hi:
        raise OverflowError(f"{name} = {_shown(v)} is outside the range it is passed in, [{lo}, {hi}]")
    return v
