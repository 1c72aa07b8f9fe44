"""RecordingWriter's pretrigger: a recording that begins just before the motion."""

import numpy as np
import pytest

from rotrod_core.reporting import recording
from rotrod_core.reporting.recording import RecordingWriter


def test_an_armed_writer_keeps_only_the_pretrigger_seconds_then_records_everything(tmp_path):
    path = tmp_path / 'r.rrd'
    writer = RecordingWriter(path, pretrigger=0.5)
    t = np.round(np.arange(0.0, 10.0, 0.01), 10)
    for k, tk in enumerate(t):
        moving = tk >= 5.0
        writer.add_state(tk, 1.0 if moving else 0.0, 0.0)
        writer.add_deflection(tk, 1e-3 * tk, 0.0)
        if moving and writer.armed:
            writer.trigger()
        if k % 25 == 0:                  # the logger's periodic flush, before and after
            writer.flush()
    writer.close()
    tw, w = recording.read_series(path, recording.OMEGA)
    tu, u = recording.read_series(path, recording.U)
    kept = t[t >= 4.5 - 1e-9]
    # nothing lost after (the timeline stores whole nanoseconds)
    assert len(tw) == len(tu) == len(kept)
    assert np.allclose(tw, kept, rtol=0, atol=2e-9) and np.allclose(tu, kept, rtol=0, atol=2e-9)
    assert np.array_equal(w, np.where(kept >= 5.0, 1.0, 0.0))
    assert np.allclose(u, 1e-3 * kept)
    assert writer.samples == len(kept)
    # time zero at the profile's start: the last stamp before the hub first moved
    assert writer.origin == pytest.approx(4.99)
    tp, _ = recording.read_component(path, recording.OMEGA, 'Scalars:scalars',
                                     recording.PROFILE_TIMELINE)
    assert np.allclose(tp, kept - 4.99, atol=2e-9)
    _, texts = recording.read_component(path, recording.EVENTS, 'TextLog:text')
    assert any('the profile starts: the hub first moves after stamp 4.990 s' in x[0]
               for x in texts)


@pytest.mark.parametrize('pretrigger', [-1.0, float('nan'), float('inf')])
def test_a_bad_pretrigger_is_refused(tmp_path, pretrigger):
    with pytest.raises(ValueError, match='pretrigger'):
        RecordingWriter(tmp_path / 'r.rrd', pretrigger=pretrigger)


def test_the_imu_readings_are_written_as_two_series_of_three_in_their_own_panel(tmp_path):
    path = tmp_path / 'r.rrd'
    writer = RecordingWriter(path, imu=True)
    t = np.round(np.arange(0.0, 1.0, 0.01), 10)
    accel = np.column_stack([np.sin(t), np.cos(t), np.full_like(t, 9.81)])
    gyro = np.column_stack([0.1 * t, -0.2 * t, 2.0 + t])
    for k, tk in enumerate(t):
        writer.add_state(tk, 0.0, 0.0)
        writer.add_imu(tk, tuple(accel[k]), tuple(gyro[k]))
    writer.close()
    ta, a = recording.read_series(path, recording.IMU_ACCELERATION)
    tg, g = recording.read_series(path, recording.IMU_ANGULAR_VELOCITY)
    assert np.allclose(ta, t, atol=2e-9) and np.allclose(tg, t, atol=2e-9)
    assert np.array_equal(a, accel) and np.array_equal(g, gyro)
    assert 'timeseries/imu' in origins(recording.blueprint(imu=True))
    assert 'timeseries/imu' not in origins(recording.blueprint())


def origins(blueprint):
    """The origins of a blueprint's views."""
    import rerun.blueprint as rrb
    found, todo = [], [blueprint.root_container]
    while todo:
        item = todo.pop()
        if isinstance(item, (rrb.Horizontal, rrb.Vertical, rrb.Grid, rrb.Tabs)):
            todo.extend(item.contents)
        elif hasattr(item, 'origin'):
            found.append(str(item.origin))
    return found
