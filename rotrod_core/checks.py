"""Validation of scalar inputs: one rule and one wording for every module."""

from __future__ import annotations

import math


def finite_number(name: str, value, *, positive: bool = False,
                  nonnegative: bool = False) -> float:
    """``value`` as a float, or ValueError naming ``name``.

    Refused: anything that is not a finite number (booleans included), and values
    not > 0 (``positive``) or not >= 0 (``nonnegative``) when asked.
    """
    if isinstance(value, bool):
        raise ValueError(f'{name} must be a number, got {value!r}')
    try:
        x = float(value)
    except OverflowError:           # an int beyond the float range
        raise ValueError(f'{name} must be finite, got {value!r}') from None
    except (TypeError, ValueError):
        raise ValueError(f'{name} must be a number, got {value!r}') from None
    if not math.isfinite(x):
        raise ValueError(f'{name} must be finite, got {value!r}')
    if positive and not x > 0:
        raise ValueError(f'{name} must be > 0, got {value!r}')
    if nonnegative and not x >= 0:
        raise ValueError(f'{name} must be >= 0, got {value!r}')
    return x
