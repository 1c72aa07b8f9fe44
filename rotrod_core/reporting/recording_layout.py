"""The default layout (blueprint) of a rotrod Rerun recording.

Left, "what did the tip do": the mechanism in 3D above the tip's path in the rotating
frame (the whole run up to the time cursor, coloured by stage as the paper's Figs. 5-8
split it). Right, the time series (deflection, hub, frequencies) and the
run's events. The viewer opens following the data: the cursor at the end of the
recording, so the whole path is drawn without any user action.
"""

from __future__ import annotations

from rotrod_core.analysis.run_events import STAGES

from .recording_scene import (
    COLOR_NAMES,
    MECHANISM,
    ROTATING,
    TRAIL,
    TRAIL_SECONDS,
    Mechanism,
    path_entity,
)

TIMELINE = 'time'
"""The message stamps, s (simulated time, or wall-clock time for a real-time run)."""
PROFILE_TIMELINE = 'profile time'
"""s from the profile's start: 0 where the hub first moves (a recording with a profile)."""
EVENTS = 'events'
"""TextLog: stage changes, the critical deflection, halts."""


def blueprint(mech: Mechanism, timeline: str = TIMELINE, imu: bool = False):
    """The default layout, a ``rerun.blueprint.Blueprint``, on ``timeline``.

    With ``imu``, a panel of the tip IMU's readings below the frequencies.
    """
    import rerun as rr
    import rerun.blueprint as rrb

    def ranges(start):
        return [rr.VisibleTimeRange(tl, start=start, end=rr.TimeRangeBoundary.cursor_relative())
                for tl in (TIMELINE, PROFILE_TIMELINE)]
    history = ranges(rr.TimeRangeBoundary.infinite())
    recent = rrb.VisibleTimeRanges(ranges(rr.TimeRangeBoundary.cursor_relative(
        seconds=-TRAIL_SECONDS)))
    paths: dict = {'/' + path_entity(s): rrb.VisibleTimeRanges(history) for s in STAGES}
    zero = ('t = 0 at the profile\'s start' if timeline == PROFILE_TIMELINE
            else 't: message stamps')
    mechanism = rrb.Spatial3DView(
        origin=MECHANISM, name=f'mechanism: disk, rod, mass; deflection drawn '
                               f'x{mech.deflection_scale:g} [m]',
        overrides={'/' + TRAIL: recent},
        eye_controls=rrb.EyeControls3D(
            kind='Orbital', position=[0.3, -0.42, 0.33],
            look_target=[0.0, 0.0, 0.4 * mech.rod_length], eye_up=[0.0, 0.0, 1.0]))
    colours = ', '.join(f'{s} {COLOR_NAMES[s]}' for s in STAGES[1:] + STAGES[:1])
    whole = rrb.Spatial2DView(origin=ROTATING, name=f'tip path (u, v) in the rotating frame '
                                                    f'[m]: {colours}',
                              overrides=paths)
    series = [
        rrb.TimeSeriesView(origin='timeseries/deflection',
                           name=f'tip deflection u, v, |r| [m] vs {zero} [s]'),
        rrb.TimeSeriesView(origin='timeseries/hub',
                           name='hub: omega [rad/s], torque [N m]; stage changes'),
        rrb.TimeSeriesView(origin='timeseries/frequencies',
                           name='dynamic frequencies f1, f2 [Hz]')]
    if imu:
        series.append(rrb.TimeSeriesView(
            origin='timeseries/imu', name='tip IMU (tip/imu, its tilted frame): specific '
                                          'force [m/s^2], angular velocity [rad/s]'))
    return rrb.Blueprint(
        rrb.Horizontal(
            rrb.Vertical(mechanism, whole, row_shares=[1, 1]),
            rrb.Vertical(
                *series,
                rrb.TextLogView(origin=EVENTS, name=f'events ({zero})'),
                row_shares=[3] * len(series) + [2]),
            column_shares=[1, 1],
        ),
        rrb.TimePanel(timeline=timeline, play_state='following', state='collapsed'),
        collapse_panels=True,
    )
