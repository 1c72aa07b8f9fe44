"""Classical fourth-order Runge-Kutta step over a state tuple.

Written with plain arithmetic on tuples, so one code path serves Python floats (the
real-time stepper, a few microseconds a step) and numpy arrays (batches).
"""

from __future__ import annotations


def rk4_step(rates, state, h, arg_start, arg_mid, arg_end):
    """Advance ``state`` by ``h`` seconds with the classical RK4 scheme.

    Args:
        rates: function ``rates(state, arg) -> tuple`` of time derivatives.
        state: tuple of floats or arrays.
        h: step, s.
        arg_start, arg_mid, arg_end: the time-dependent input (e.g. hub torque) at the
            start, middle and end of the step.
    """
    half = 0.5 * h
    k1 = rates(state, arg_start)
    k2 = rates(tuple(y + half * k for y, k in zip(state, k1)), arg_mid)
    k3 = rates(tuple(y + half * k for y, k in zip(state, k2)), arg_mid)
    k4 = rates(tuple(y + h * k for y, k in zip(state, k3)), arg_end)
    sixth = h / 6.0
    return tuple(y + sixth * (a + 2.0 * b + 2.0 * c + d)
                 for y, a, b, c, d in zip(state, k1, k2, k3, k4))
