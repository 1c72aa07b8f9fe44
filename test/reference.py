"""Independent reference formulas from docs/model.md, written apart from rotrod_core's code."""

import math

import numpy as np
from scipy.integrate import solve_ivp

M, L, D, E, R0 = 0.3, 0.3, 0.003, 100e9, 0.1
I_AREA = math.pi * D**4 / 64
K = 3 * E * I_AREA / L**3
W0 = math.sqrt(K / M)

# The real rig of config/real_rig.yaml (docs/real_rig.md), written out here: Table 1
# upright under gravity G with a steel rod; the exact tip-load stiffness less the rod's
# weight as a Rayleigh geometric stiffness, and one-mode Rayleigh-Ritz masses.
G, STEEL = 9.81, 7850.0
AREA = math.pi * D**2 / 4
KAPPA = math.sqrt(M * G / (E * I_AREA))
K_RIG = M * G / (math.tan(KAPPA * L) / KAPPA - L) - 3 / 8 * STEEL * AREA * G
MODAL_MASS_RIG = M + 33 / 140 * STEEL * AREA * L
ECCENTRIC_MASS_RIG = M + 3 / 8 * STEEL * AREA * L
W0_RIG = math.sqrt(K_RIG / MODAL_MASS_RIG)
LOAD_RADIUS_RIG = R0 * ECCENTRIC_MASS_RIG / MODAL_MASS_RIG


def step_start(t, w, w0=W0, r0=R0):
    """Eq. 29: z = u + i v from rest in the rotating frame at constant w (< w0)."""
    w1, w2 = w0 - w, w0 + w
    return (w**2 * r0 / (2 * w0)) * ((1 - np.exp(1j * w1 * t)) / w1
                                     + (1 - np.exp(-1j * w2 * t)) / w2)


def impulsive_start(t, w, w0=W0, r0=R0):
    """Mass at rest in the inertial frame when w jumps from 0 (t from the jump).

    Inertial frame: Z'' + w0^2 Z = w0^2 r0 exp(i w t), Z(0) = r0, Z'(0) = 0;
    deflection z = exp(-i w t) Z - r0.
    """
    a = w0**2 - w**2
    Z = (w0**2 * r0 / a) * np.exp(1j * w * t) - (w**2 * r0 / a) * np.cos(w0 * t) \
        - 1j * (w * w0 * r0 / a) * np.sin(w0 * t)
    return np.exp(-1j * w * t) * Z - r0


def reference_run(omega, omega_dot, t_eval, w0=W0, r0=R0, rtol=1e-12, atol=1e-15):
    """Tight DOP853 on the complex form z'' + 2iw z' + (w0^2 - w^2 + iw') z = r0 (w^2 - iw')."""
    def rhs(t, y):
        z = y[0] + 1j * y[1]
        dz = y[2] + 1j * y[3]
        w, wd = omega(t), omega_dot(t)
        ddz = r0 * (w * w - 1j * wd) - 2j * w * dz - (w0**2 - w * w + 1j * wd) * z
        return [dz.real, dz.imag, ddz.real, ddz.imag]

    sol = solve_ivp(rhs, (t_eval[0], t_eval[-1]), [0, 0, 0, 0], method='DOP853', rtol=rtol,
                    atol=atol, t_eval=t_eval)
    return sol.y[0], sol.y[1]


def eq26(t, T=15.0, W=2.0):
    """Eq. 26 angular velocity and acceleration at a scalar time (written from docs/model.md)."""
    if t <= T:
        return W * (t / T - math.sin(2 * math.pi * t / T) / (2 * math.pi)), \
            W / T * (1 - math.cos(2 * math.pi * t / T))
    if t <= 4 * T / 3:
        return W, 0.0
    if t <= 7 * T / 3:
        s = t - 4 * T / 3
        return W * (1 - s / T + math.sin(2 * math.pi * s / T) / (2 * math.pi)), \
            W / T * (math.cos(2 * math.pi * s / T) - 1)
    return 0.0, 0.0


def rk4_phase_bound(h, w, t, amplitude):
    """Twice classical RK4's phase error after time t: ~ (h w)^4 w t / 120 x amplitude."""
    return 2 * (h * w) ** 4 * w * t / 120 * amplitude


def peak_frequency(x, dt: float, low: float, high: float) -> float:
    """The frequency (Hz) of the largest spectral peak of samples ``x`` (every ``dt`` s)
    between ``low`` and ``high`` Hz: Hann window, zero-padded eightfold."""
    x = np.asarray(x) - np.mean(x)
    spectrum = np.abs(np.fft.rfft(x * np.hanning(len(x)), 8 * len(x)))
    f = np.fft.rfftfreq(8 * len(x), dt)
    band = (f > low) & (f < high)
    return float(f[band][np.argmax(spectrum[band])])
