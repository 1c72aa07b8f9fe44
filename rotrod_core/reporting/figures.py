"""PNG figures: the paper's Figs. 3-10 and the analyses beyond it (matplotlib, headless).

matplotlib is imported when a figure is drawn, not with this module, and only its
object API is used (``matplotlib.figure.Figure``, rendered by Agg): no pyplot, no
window, no global backend switch. Every figure has a fixed size in inches at
:data:`DPI`, so its size in pixels is known: :data:`PAPER_SIZE` (640 x 480 px) for
the paper's figures, wider ones for the multi-panel analyses. Axes are labelled with
units; deflections are shown in mm or um as labelled (the data are in m).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from rotrod_core.analysis.critical import STARTS, critical_speed
from rotrod_core.analysis.modes import dynamic_frequencies
from rotrod_core.analysis.stages import eq26_stages

DPI = 100
"""Dots per inch of every PNG."""

PAPER_SIZE = (6.4, 4.8)
"""Figs. 3-10: 640 x 480 px."""

CAMPBELL_SIZE = (12.8, 6.4)
"""Campbell diagrams (2 x 4 panels): 1280 x 640 px."""

MAP_SIZE = (12.8, 8.0)
"""Critical-speed maps (2 x 3 panels): 1280 x 800 px."""

DRIFT_SIZE = (12.8, 4.8)
"""Coupling drift (2 panels): 1280 x 480 px."""

PLAN_SIZE = (12.8, 4.8)
"""A planned spin-up beside Eq. 26 (3 panels): 1280 x 480 px."""
PLAN_COLORS = {'plan': '#1f77b4', 'eq26': '#7f7f7f'}

STAGE_COLORS = {'spin-up': '#1f77b4', 'hold': '#2ca02c', 'spin-down': '#d62728',
                'rest': '#9467bd'}
WHIRL_COLORS = {'forward': '#1f77b4', 'backward': '#d62728', 'none': '#7f7f7f'}
WHIRL_LABELS = {'forward': 'forward', 'backward': 'backward', 'none': 'none (real pair)'}
GROWTH_SPAN = 0.5
"""Smallest half-range of the growth-rate axes, 1/s."""
START_LABELS = {'quasi_static': 'quasi-static (closed form)', 'step': 'step (closed form)',
                'impulsive': 'impulsive (closed form)'}
MM, UM = 1e3, 1e6
R0_TICKS = (0.005, 0.01, 0.02, 0.05, 0.1, 0.2)
"""Tick values of eccentricity axes, m."""
LIMIT_TICKS_MM = (1.0, 2.0, 3.0, 5.0, 9.0)
"""Tick values of deflection-limit axes, mm."""


def _figure(size, nrows=1, ncols=1, **kwargs):
    from matplotlib.figure import Figure
    fig = Figure(figsize=size, dpi=DPI, layout='constrained')
    return fig, fig.subplots(nrows, ncols, squeeze=False, **kwargs)


def _save(fig, path) -> Path:
    path = Path(path)
    fig.savefig(path, dpi=DPI, format='png', metadata={'Software': None})
    return path


def require_matplotlib() -> None:
    """Raise ImportError with the remedy when matplotlib is missing."""
    try:
        import matplotlib  # noqa: F401
    except ImportError:
        raise ImportError("the figures need matplotlib: pip install 'rotrod[viz]' "
                          '(or pip install matplotlib)') from None


def angular_velocity(run, profile, path) -> Path:
    """Fig. 3: w(t) of the run, stage boundaries marked."""
    fig, ax = _figure(PAPER_SIZE)
    ax = ax[0, 0]
    ax.plot(run.t, run.omega, color='k', lw=1.5)
    for name, a, b in eq26_stages(profile.period, float(run.t[-1])):
        ax.axvspan(a, b, color=STAGE_COLORS[name], alpha=0.08, lw=0)
        ax.text(0.5 * (a + b), 1.04 * profile.peak, name, ha='center', va='bottom', fontsize=9)
    ax.set_xlim(run.t[0], run.t[-1])
    ax.set_ylim(-0.05 * profile.peak, 1.15 * profile.peak)
    ax.set_xlabel('time t [s]')
    ax.set_ylabel(r'angular velocity $\omega$ [rad/s]')
    ax.set_title(f'Fig. 3: Eq. 26, T = {profile.period:g} s, W = {profile.omega_target:g} rad/s')
    ax.grid(alpha=0.3)
    return _save(fig, path)


def _trajectory(ax, u, v, scale, color, label=None):
    ax.plot(scale * u, scale * v, color=color, lw=0.7, label=label)
    ax.plot(scale * u[0], scale * v[0], 'o', color=color, ms=5, mfc='white')
    ax.plot(scale * u[-1], scale * v[-1], 's', color=color, ms=5)


def trajectory(run, profile, path) -> Path:
    """Fig. 4: the whole run's trajectory (u, v) in the rotating frame, by stage."""
    fig, ax = _figure(PAPER_SIZE)
    ax = ax[0, 0]
    for name, a, b in eq26_stages(profile.period, float(run.t[-1])):
        w = run.window(a, b)
        _trajectory(ax, w.u, w.v, MM, STAGE_COLORS[name], f'{name} ({a:g}-{b:g} s)')
    ax.set_xlabel('radial deflection u [mm]')
    ax.set_ylabel('tangential deflection v [mm]')
    ax.set_title('Fig. 4: trajectory of the mass in the rotating frame, '
                 f'{run.t[0]:g}-{run.t[-1]:g} s')
    ax.legend(fontsize=8, loc='upper left')
    ax.grid(alpha=0.3)
    return _save(fig, path)


def stage_trajectory(run, profile, stage: str, figure_number: int, path,
                     centre: float = 0.0) -> Path:
    """Figs. 5-8: the trajectory within one stage (o = start, square = end).

    Spin-up and spin-down in mm; hold and rest in um with equal axes (their motion is
    sub-micrometre), the hold about u = ``centre`` (m).
    """
    stages = {n: (a, b) for n, a, b in eq26_stages(profile.period, float(run.t[-1]))}
    a, b = stages[stage]
    w = run.window(a, b)
    fig, ax = _figure(PAPER_SIZE)
    ax = ax[0, 0]
    small = stage in ('hold', 'rest')
    scale, unit = (UM, 'µm') if small else (MM, 'mm')
    _trajectory(ax, w.u - centre, w.v, scale, STAGE_COLORS[stage])
    if small:
        ax.set_aspect('equal', adjustable='datalim')
    shift = f' - {MM * centre:.6f} mm' if centre else ''
    ax.set_xlabel(f'radial deflection u{shift} [{unit}]')
    ax.set_ylabel(f'tangential deflection v [{unit}]')
    ax.set_title(f'Fig. {figure_number}: trajectory in the rotating frame, {a:g}-{b:g} s '
                 f'({stage})', fontsize=10)
    ax.grid(alpha=0.3)
    return _save(fig, path)


def dynamic_frequency_plot(params, rows, path) -> Path:
    """Fig. 9: f1 and f2 vs w, Eq. 28 (lines) and fitted to simulations (markers)."""
    w0 = float(params.natural_frequency)
    fig, ax = _figure(PAPER_SIZE)
    ax = ax[0, 0]
    w = np.linspace(0.0, w0, 200)
    f1, f2 = dynamic_frequencies(params, w)
    ax.plot(w, f1, color=WHIRL_COLORS['forward'], label=r'$f_1 = (\omega_0 - \omega)/2\pi$')
    ax.plot(w, f2, color=WHIRL_COLORS['backward'], label=r'$f_2 = (\omega_0 + \omega)/2\pi$')
    om = [r.omega for r in rows]
    ax.plot(om, [r.f1_measured for r in rows], 'o', color=WHIRL_COLORS['forward'], mfc='none',
            label=r'$f_1$ measured (forward whirl)')
    ax.plot(om, [r.f2_measured for r in rows], 's', color=WHIRL_COLORS['backward'],
            mfc='none', label=r'$f_2$ measured (backward whirl)')
    ax.axvline(w0, color='k', ls=':', lw=1)
    ax.text(w0, 0.02, r' $\omega_0$', ha='right', va='bottom', fontsize=9)
    ax.set_xlabel(r'constant angular velocity $\omega$ [rad/s]')
    ax.set_ylabel('dynamic frequency [Hz]')
    ax.set_title('Fig. 9: dynamic frequencies, Eq. 28 and simulated runs')
    ax.set_xlim(0, 1.05 * w0)
    ax.set_ylim(0, None)
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    return _save(fig, path)


def critical_speed_plot(params, rows, limit, path) -> Path:
    """Fig. 10: critical speed vs r0, closed forms (lines) and numerical (markers)."""
    w0 = float(params.natural_frequency)
    r_max = max(r.eccentricity for r in rows)
    r0 = np.linspace(0.0, r_max, 300)
    fig, ax = _figure(PAPER_SIZE)
    ax = ax[0, 0]
    styles = {'quasi_static': '-', 'step': '--', 'impulsive': ':'}
    for start in STARTS:
        ax.plot(r0, critical_speed(params.replace(eccentricity=r0), limit, start), 'k',
                ls=styles[start], lw=1.2, label=START_LABELS[start])
    forced = [r for r in rows if r.eccentricity > 0]
    ax.plot([r.eccentricity for r in forced], [r.eq26_numerical for r in forced], 'o',
            color='#d62728', mfc='none', label='Eq. 26 shape (numerical)')
    ax.plot([r.eccentricity for r in forced], [r.step_numerical for r in forced], 's',
            color='#1f77b4', mfc='none', label='step from rest (numerical)')
    ax.axhline(w0, color='gray', lw=0.8)
    ax.set_xlabel('initial eccentricity $r_0$ [m]')
    ax.set_ylabel(r'critical angular velocity $\omega_{cr}$ [rad/s]')
    ax.set_title(f'Fig. 10: critical speed for a {MM * limit:.1f} mm deflection limit')
    ax.set_xlim(0, r_max)
    ax.set_ylim(0, 1.05 * w0)
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    return _save(fig, path)


def campbell_plot(cases: dict, path) -> Path:
    """Campbell diagrams: frequencies by whirl (top) and growth rates (bottom) vs w.

    ``cases`` maps a title to a :class:`~rotrod_core.analysis.modes.CampbellDiagram`;
    unstable bands are shaded red.
    """
    fig, axes = _figure(CAMPBELL_SIZE, 2, len(cases), sharex='col')
    for j, (title, c) in enumerate(cases.items()):
        top, bottom = axes[0, j], axes[1, j]
        for whirl, color in WHIRL_COLORS.items():
            mask = c.whirl == whirl
            if np.any(mask):
                om = np.broadcast_to(c.omega[:, None], mask.shape)[mask]
                top.plot(om, c.frequencies[mask], '.', ms=2.5, color=color,
                         label=WHIRL_LABELS[whirl])
                bottom.plot(om, c.growth_rates[mask], '.', ms=2.5, color=color)
        for lo, hi in c.unstable_bands:
            for ax in (top, bottom):
                ax.axvspan(lo, hi, color='red', alpha=0.15, lw=0)
        bottom.axhline(0.0, color='k', lw=0.6)
        # rounding-level rates (1e-15) are not drawn as structure: at least +-0.5 1/s
        span = max(GROWTH_SPAN, 1.1 * float(np.nanmax(np.abs(c.growth_rates))))
        bottom.set_ylim(-span, span)
        top.set_title(title, fontsize=10)
        top.set_ylim(0, None)
        bottom.set_xlabel(r'angular velocity $\omega$ [rad/s]')
        top.legend(title='whirl', fontsize=8, markerscale=3, loc='upper left')
        if j == 0:
            top.set_ylabel('frequency, rotating frame [Hz]')
            bottom.set_ylabel(r'growth rate Re $\lambda$ [1/s]')
        for ax in (top, bottom):
            ax.grid(alpha=0.3)
            ax.set_xlim(c.omega[0], c.omega[-1])
    fig.suptitle('Campbell diagrams (unstable bands shaded)')
    return _save(fig, path)


def _log_axes(ax, r0, d_mm):
    from matplotlib.ticker import FixedLocator, NullFormatter, NullLocator
    ax.set_xscale('log')
    ax.set_yscale('log')
    for axis, ticks, values in ((ax.xaxis, R0_TICKS, r0), (ax.yaxis, LIMIT_TICKS_MM, d_mm)):
        shown = [t for t in ticks if values[0] <= t <= values[-1]]
        axis.set_major_locator(FixedLocator(shown))
        axis.set_major_formatter(lambda x, _: f'{x:g}')
        axis.set_minor_locator(NullLocator())
        axis.set_minor_formatter(NullFormatter())
    ax.set_xlabel('eccentricity $r_0$ [m]')
    ax.set_ylabel(r'deflection limit $\delta$ [mm]')


def critical_map_plot(cmap, label: str, reference_limit: float, path) -> Path:
    """Critical-speed maps over (r0, delta), one per start.

    Below them: the collapse of every map on delta / r0, and the numerical map's
    difference from the quasi-static closed form.
    """
    from matplotlib.figure import Figure

    w0 = cmap.natural_frequency
    r0, d_mm = cmap.eccentricity, MM * cmap.limit
    names = list(STARTS) + [label]
    titles = dict(START_LABELS, **{label: f'{label} shape (numerical, dt = '
                                          f'{cmap.numerical_step:g} s)'})
    fig = Figure(figsize=MAP_SIZE, dpi=DPI, layout='constrained')
    top, bottom = fig.subfigures(2, 1)  # type: ignore[misc]  # an array of two
    maps = top.subplots(1, 4)
    levels = np.linspace(0.0, w0, 25)
    cs = None
    for ax, name in zip(maps, names):
        cs = ax.contourf(r0, d_mm, cmap.speeds[name], levels=levels, cmap='viridis')
        ax.contour(r0, d_mm, cmap.speeds[name], levels=levels[::4], colors='w',
                   linewidths=0.5)
        ax.axhline(MM * reference_limit, color='r', lw=0.8, ls='--')
        _log_axes(ax, r0, d_mm)
        ax.set_title(titles[name], fontsize=9)
    top.colorbar(cs, ax=list(maps), label=r'$\omega_{cr}$ [rad/s]')
    top.suptitle(r'critical angular velocity $\omega_{cr}$ over eccentricity and deflection '
                 f'limit (dashed: {MM * reference_limit:g} mm)')
    collapse, difference = bottom.subplots(1, 2)
    ratio = (cmap.limit[:, None] / r0[None, :]).ravel()
    order = np.argsort(ratio)
    for name, style in zip(STARTS, ('-', '--', ':')):
        collapse.plot(ratio[order], cmap.speeds[name].ravel()[order] / w0, 'k', ls=style,
                      lw=1, label=START_LABELS[name])
    collapse.plot(ratio, cmap.speeds[label].ravel() / w0, '.', color='#d62728', ms=3,
                  label=f'{label} shape (numerical, every grid point)')
    collapse.set_xscale('log')
    collapse.set_xlabel(r'$\delta / r_0$ [-]')
    collapse.set_ylabel(r'$\omega_{cr} / \omega_0$ [-]')
    collapse.set_title('every map depends on delta / r0 only', fontsize=10)
    collapse.legend(fontsize=8)
    collapse.grid(alpha=0.3)
    diff = 100.0 * (cmap.speeds[label] / cmap.speeds['quasi_static'] - 1.0)
    lim = max(float(np.max(np.abs(diff))), 1e-6)
    cd = difference.pcolormesh(r0, d_mm, diff, cmap='RdBu_r', vmin=-lim, vmax=lim,
                               shading='nearest')
    bottom.colorbar(cd, ax=difference, label='difference [%]')
    _log_axes(difference, r0, d_mm)
    difference.set_title(f'{label} shape (numerical) vs quasi-static closed form',
                         fontsize=10)
    return _save(fig, path)


def coupling_drift_plot(drifts: dict, path) -> Path:
    """|relative drift| of energy and angular momentum vs time, one line per coupling."""
    fig, axes = _figure(DRIFT_SIZE, 1, 2)
    floor = 1e-17
    names = {'exact': 'exact (Lagrangian) coupling', 'paper': "paper's Eq. 23 + J w'"}
    colors = {'exact': '#1f77b4', 'paper': '#d62728'}
    for coupling, d in drifts.items():
        for ax, series in zip(axes[0], (d.energy, d.angular_momentum)):
            ax.semilogy(d.t, np.maximum(np.abs(series), floor), color=colors[coupling],
                        lw=0.8, label=names.get(coupling, coupling))
    for ax, what, formula in zip(axes[0], ('energy', 'angular momentum'),
                                 ('|E(t) - E(0)| / E(0)', '|L(t) - L(0)| / L(0)')):
        ax.set_xlabel('time t [s]')
        ax.set_ylabel(f'relative change of {what} [-]')
        ax.set_title(f'{what}: {formula}', fontsize=10)
        ax.set_ylim(floor / 2, 1.0)
        ax.grid(alpha=0.3, which='both')
        ax.legend(fontsize=8, loc='center right')
    fig.suptitle('free rotation, hub torque Q = 0: drift of the invariants '
                 f'(values below {floor:g} drawn at {floor:g})')
    return _save(fig, path)


def spin_up_plan(plan, run, path, reference=None, reference_run=None,
                 deflection_limit=None) -> Path:
    """A planned change of speed: w, w' and the tip path in the rotating frame.

    Times are drawn as fractions of each profile's duration, so that the shapes
    compare; the legend gives the durations.

    ``run`` is the plan's predicted run; ``reference`` (with ``reference_run``), if
    given, is drawn beside it in grey (Eq. 26 for a spin-up from rest).
    """
    fig, ax = _figure(PLAN_SIZE, 1, 3)
    curves = [('plan', run,
               f'plan: {plan.duration:.3g} s, residual {UM * plan.residual_amplitude:.3g} µm')]
    if reference is not None:
        curves.append(('eq26', reference_run,
                       f'Eq. 26 spin-up: {reference.period:g} s'))
    for key, r, label in curves:
        color = PLAN_COLORS[key]
        duration = plan.duration if key == 'plan' else reference.period
        ax[0, 0].plot(r.t / duration, r.omega, color=color, lw=1.5, label=label)
        ax[0, 1].plot(r.t / duration, r.omega_dot, color=color, lw=1.5, label=label)
        _trajectory(ax[0, 2], r.u, r.v, MM, color, label)
    if deflection_limit is not None:
        phi = np.linspace(-0.6, 0.6, 200)
        ax[0, 2].plot(MM * deflection_limit * np.cos(phi), MM * deflection_limit * np.sin(phi),
                      'r--', lw=1, label=f'|r| = {MM * deflection_limit:g} mm')
    ax[0, 0].set_xlabel('time / duration of each profile')
    ax[0, 0].set_ylabel(r'angular velocity $\omega$ [rad/s]')
    ax[0, 1].set_xlabel('time / duration of each profile')
    ax[0, 1].set_ylabel(r"angular acceleration $\dot\omega$ [rad/s$^2$]")
    ax[0, 2].set_xlabel('radial deflection u [mm]')
    ax[0, 2].set_ylabel('tangential deflection v [mm]')
    ax[0, 0].set_title('angular velocity', fontsize=10)
    ax[0, 1].set_title('angular acceleration', fontsize=10)
    ax[0, 2].set_title(f'tip path in the rotating frame (peak '
                       f'{MM * plan.peak_deflection:.4g} mm)', fontsize=10)
    for a in ax[0]:
        a.grid(alpha=0.3)
        a.legend(fontsize=8, loc='best')
    return _save(fig, path)


SPIN_UP_COLORS = ('#7f7f7f', '#d62728', '#ff7f0e', '#1f77b4')
"""Eq. 26 grey, then the planned spin-ups of :mod:`rotrod_core.reporting.spin_ups`."""


def spin_up_comparison(rows, path, deflection_limit) -> Path:
    """Eq. 26 beside planned spin-ups: w(t), w'(t) and the tip path in the rotating frame.

    ``rows``: :class:`rotrod_core.reporting.spin_ups.SpinUp` (time on a common axis, s).
    """
    fig, ax = _figure(PLAN_SIZE, 1, 3)
    for row, color in zip(rows, SPIN_UP_COLORS):
        r = row.run
        label = (f'{row.label.split(" (")[0]}: {row.duration:.3g} s, '
                 f'residual {UM * row.residual:.2g} µm')
        ax[0, 0].plot(r.t, r.omega, color=color, lw=1.5, label=label)
        ax[0, 1].plot(r.t, r.omega_dot, color=color, lw=1.2, label=label)
        _trajectory(ax[0, 2], r.u, r.v, MM, color, label)
    phi = np.linspace(-0.6, 0.6, 200)
    ax[0, 2].set_ylim(-3.3, 2.2)
    ax[0, 2].plot(MM * deflection_limit * np.cos(phi), MM * deflection_limit * np.sin(phi),
                  'k--', lw=1, label=f'|r| = {MM * deflection_limit:g} mm')
    ax[0, 1].set_yscale('symlog', linthresh=0.5)
    for a in ax[0, :2]:
        a.set_xlabel('time t [s]')
    ax[0, 0].set_ylabel(r'angular velocity $\omega$ [rad/s]')
    ax[0, 1].set_ylabel(r"angular acceleration $\dot\omega$ [rad/s$^2$]")
    ax[0, 2].set_xlabel('radial deflection u [mm]')
    ax[0, 2].set_ylabel('tangential deflection v [mm]')
    ax[0, 0].set_title('angular velocity', fontsize=10)
    ax[0, 1].set_title("angular acceleration (linear within 0.5, then log)", fontsize=10)
    ax[0, 2].set_title('tip path in the rotating frame', fontsize=10)
    for a in ax[0]:
        a.grid(alpha=0.3)
    ax[0, 2].legend(fontsize=7, loc='upper left')
    return _save(fig, path)
