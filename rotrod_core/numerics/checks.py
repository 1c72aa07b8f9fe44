"""Validation of scalar inputs: one rule and one wording for every module."""

from __future__ import annotations

import math

import numpy as np


class NonFiniteStateError(FloatingPointError):
    """A step produced a non-finite state; the stepper kept its last good state."""


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


def finite_array(name: str, value) -> np.ndarray:
    """``value`` as a float array, or ValueError naming ``name`` and the first bad entry.

    The array counterpart of :func:`finite_number`: refused are values that are not
    numbers or arrays of numbers, and any entry that is NaN or infinite.
    """
    try:
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError, OverflowError):
        raise ValueError(f'{name} must be a number or an array of numbers, '
                         f'got {value!r}') from None
    finite = np.isfinite(arr)
    if not finite.all():
        if arr.ndim == 0:
            raise ValueError(f'{name} must be finite, got {value!r}')
        i = np.unravel_index(int(np.argmax(~finite.ravel())), arr.shape)
        index = ', '.join(str(int(k)) for k in i)
        raise ValueError(f'{name} must be finite: {name}[{index}] = {arr[i]!r}')
    return arr
