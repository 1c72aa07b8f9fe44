"""Forward-mode dual numbers: exact derivatives of plain arithmetic.

A :class:`Dual` carries a value and its derivative along one direction. Evaluating a
function written with ``+``, ``-`` and ``*`` (the equations of motion are) on duals gives
the function's value and its exact derivative, with no second copy of the formula:
:mod:`rotrod_core.model.propagation` differentiates the one source of the equations
this way. Values and derivatives may be floats or numpy arrays (they broadcast).
"""

from __future__ import annotations


class Dual:
    """A value and its derivative along one direction (any units: d value / d input)."""

    __slots__ = ('value', 'deriv')
    __array_ufunc__ = None          # numpy defers to the reflected operators below

    def __init__(self, value, deriv):
        self.value = value
        self.deriv = deriv

    def __add__(self, other):
        if isinstance(other, Dual):
            return Dual(self.value + other.value, self.deriv + other.deriv)
        return Dual(self.value + other, self.deriv)

    __radd__ = __add__

    def __sub__(self, other):
        if isinstance(other, Dual):
            return Dual(self.value - other.value, self.deriv - other.deriv)
        return Dual(self.value - other, self.deriv)

    def __rsub__(self, other):
        return Dual(other - self.value, -self.deriv)

    def __mul__(self, other):
        if isinstance(other, Dual):
            return Dual(self.value * other.value,
                        self.deriv * other.value + self.value * other.deriv)
        return Dual(self.value * other, self.deriv * other)

    __rmul__ = __mul__

    def __neg__(self):
        return Dual(-self.value, -self.deriv)

    def __repr__(self) -> str:
        return f'Dual({self.value!r}, {self.deriv!r})'


def value_of(x):
    """The value of ``x`` (a :class:`Dual` or a plain number or array)."""
    return x.value if isinstance(x, Dual) else x


def derivative_of(x):
    """The derivative carried by ``x``; 0.0 for a plain number or array (a constant)."""
    return x.deriv if isinstance(x, Dual) else 0.0
