"""The hub's drive as a real rig has it: a velocity servo, and the bearing's friction.

The servo has a torque limit; the friction is viscous and Coulomb.

**Servo** (``drive: servo``): a digital PI speed loop at the physics rate. At each step
it reads the hub speed w and the reference w_ref (the shaped setpoints or the
trajectory, as the ideal velocity drive follows them) and holds over the step the
motor torque

    Q = clip(Kp e + I, -Q_max, Q_max),   e = w_ref - w,   I <- I + Ki e dt,

the integral frozen while Q is saturated in the direction e pushes it (conditional
integration, against wind-up). The torque acts on the hub through the coupling
(``rotrod_core.model.equations.hub_angular_acceleration``), so the rod's reaction
torque disturbs the speed as on a rig. The gains place the closed loop of a rigid hub,
J w' = Q with J = Je + M re^2 (hub, rod and mass turning rigidly upright), at natural
frequency w_n = 2 pi ``bandwidth`` and damping ``damping``:

    Kp = 2 damping w_n J,   Ki = w_n^2 J,

so that w / w_ref = (2 damping w_n s + w_n^2) / (s^2 + 2 damping w_n s + w_n^2).
At damping 1 its step response is 1 - exp(-w_n t) (1 - w_n t): 13.5 % overshoot (1 +
exp(-2)) at t = 2 / w_n.

**Bearing friction**, on the hub in the torque and servo drives: viscous c w plus
Coulomb Q_c, held over each step as the servo's torque is,

    Q_f = -c w - Q_c sign(w)                  when |w| > w_stick,
    Q_f = -c w - clip(Q_load, -Q_c, Q_c)      within it (stiction: a load up to Q_c, the
                                              drive's torque and the rod's reaction
                                              (exact coupling), holds the hub),

w_stick = Q_c dt / J, the speed one step of Coulomb friction takes away (Karnopp's
band: without it the sign flips every step about w = 0). The ideal velocity drive
imposes w whatever the friction: its torque includes what overcomes it.
"""

from __future__ import annotations

import math

import numpy as np

from rotrod_core.model.equations import Coefficients

FOLLOWS_OMEGA = ('velocity', 'servo')
"""The drives fed by cmd/omega and trajectories (angular-velocity references)."""


def rigid_inertia(co: Coefficients):
    """Je + M re^2, kg m^2: hub, rod and mass turning rigidly, upright."""
    return co.rotor_inertia + co.modal_mass * co.load_radius ** 2


def servo_gains(co: Coefficients, bandwidth: float, damping: float) -> tuple:
    """(Kp N m s/rad, Ki N m/rad) of the PI speed loop (see the module)."""
    wn = 2.0 * math.pi * bandwidth
    inertia = rigid_inertia(co)
    return 2.0 * damping * wn * inertia, wn * wn * inertia


def servo_torque(kp, ki, max_torque, integral, w_ref, omega, dt: float):
    """(torque N m, the new integral N m) of one step of the PI loop.

    Floats or arrays (one per rod) alike.
    """
    error = w_ref - omega
    raw = kp * error + integral
    grow = ki * error * dt
    if isinstance(raw, float):
        torque = min(max(raw, -max_torque), max_torque)
        if torque == raw or (raw > torque) != (grow > 0):
            integral = integral + grow
        return torque, integral
    torque = np.clip(raw, -max_torque, max_torque)
    integral = np.where((torque == raw) | ((raw > torque) != (grow > 0)), integral + grow,
                        integral)
    return torque, integral


def friction_torque(viscous, coulomb, stick, omega, load):
    """The bearing's torque on the hub, N m (see the module); floats or arrays.

    ``load``: the other torques on the hub (N m), which stiction holds up to Q_c.
    """
    if isinstance(omega, float):
        if not coulomb:
            return -viscous * omega
        if abs(omega) > stick:
            return -viscous * omega - math.copysign(coulomb, omega)
        return -viscous * omega - min(max(load, -coulomb), coulomb)
    slipping = np.abs(omega) > stick
    return -viscous * omega - np.where(slipping, coulomb * np.sign(omega),
                                       np.clip(load, -coulomb, coulomb))


def overcome_friction(viscous, coulomb, omega):
    """The torque the ideal velocity drive adds to overcome the bearing, N m."""
    if isinstance(omega, float):
        return viscous * omega + (math.copysign(coulomb, omega) if omega else 0.0)
    return viscous * omega + coulomb * np.sign(omega)


__all__ = ['FOLLOWS_OMEGA', 'friction_torque', 'overcome_friction', 'rigid_inertia',
           'servo_gains', 'servo_torque']
