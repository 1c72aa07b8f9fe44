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


def rk4_step_prescribed_rotation(accelerations, state, h, omega_dot):
    """:func:`rk4_step` for a rotation with constant angular acceleration over the step.

    ``state`` is (u, v, u', v', theta, omega) of Python floats; ``accelerations(u, v,
    u', v', omega, omega_dot) -> (u'', v'')``. The same arithmetic as :func:`rk4_step`
    with ``rates = (u', v', u'', v'', omega, omega_dot)`` (so the same result to the
    bit), written out for the real-time stepper, where the tuple expressions cost more
    than the arithmetic.
    """
    u, v, du, dv, theta, omega = state
    half = 0.5 * h
    wd = omega_dot
    w2 = omega + half * wd
    w4 = omega + h * wd
    a1u, a1v = accelerations(u, v, du, dv, omega, wd)
    u2, v2, du2, dv2 = u + half * du, v + half * dv, du + half * a1u, dv + half * a1v
    a2u, a2v = accelerations(u2, v2, du2, dv2, w2, wd)
    u3, v3, du3, dv3 = u + half * du2, v + half * dv2, du + half * a2u, dv + half * a2v
    a3u, a3v = accelerations(u3, v3, du3, dv3, w2, wd)
    u4, v4, du4, dv4 = u + h * du3, v + h * dv3, du + h * a3u, dv + h * a3v
    a4u, a4v = accelerations(u4, v4, du4, dv4, w4, wd)
    sixth = h / 6.0
    return (u + sixth * (du + 2.0 * du2 + 2.0 * du3 + du4),
            v + sixth * (dv + 2.0 * dv2 + 2.0 * dv3 + dv4),
            du + sixth * (a1u + 2.0 * a2u + 2.0 * a3u + a4u),
            dv + sixth * (a1v + 2.0 * a2v + 2.0 * a3v + a4v),
            theta + sixth * (omega + 2.0 * w2 + 2.0 * w2 + w4),
            omega + sixth * (wd + 2.0 * wd + 2.0 * wd + wd))
