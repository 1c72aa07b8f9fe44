"""The mechanism in 3D and the rotating-frame path of a recording, read back from the file
and checked against closed forms: the disk turns by theta, the rod is the tip-loaded
cantilever from its root at r0 to the mass, the path is split by the Eq. 26 stages."""

import math

import numpy as np
import pytest
from reference import R0, L

from rotrod_core import Eq26Profile, RodParams, simulate
from rotrod_core.analysis.stages import eq26_stages
from rotrod_core.model.geometry import cantilever_shape
from rotrod_core.reporting import recording
from rotrod_core.reporting import recording_scene as scene3d
from rotrod_core.reporting.recording_layout import PROFILE_TIMELINE
from rotrod_core.reporting.recording_scene import Mechanism

SCALE = 20.0


@pytest.fixture(scope='module')
def eq26(tmp_path_factory):
    """The Eq. 26 run, written at the markers' scale and at true size."""
    run = simulate(RodParams(), Eq26Profile(period=15.0, omega_target=2.0), 40.0, dt=1e-3)
    out = tmp_path_factory.mktemp('scene')
    drawn, true = out / 'drawn.rrd', out / 'true.rrd'
    recording.write_run(drawn, run)
    recording.write_run(true, run, mechanism=Mechanism.from_params(run.params,
                                                                   deflection_scale=1.0))
    t, _ = recording.read_series(drawn, recording.U)
    k = np.round(t / 1e-3).astype(int)
    return run, k, drawn, true


def rows(path, entity, column, timeline=recording.TIMELINE):
    return recording.read_component(path, entity, column, timeline)


def test_the_disk_turns_by_the_hub_angle(eq26):
    run, k, drawn, _ = eq26
    t, q = rows(drawn, scene3d.HUB, 'Transform3D:quaternion')
    q = np.array([r.reshape(4) for r in q])                  # (x, y, z, w)
    assert np.array_equal(np.round(t / 1e-3).astype(int), k)
    assert np.allclose(q[:, :2], 0.0)                        # about the axis z
    angle = 2 * np.arctan2(q[:, 2], q[:, 3])
    wrapped = np.angle(np.exp(1j * (angle - run.theta[k])))
    assert np.max(np.abs(wrapped)) < 1e-6                    # float32 quaternions


def test_the_rods_tip_is_the_mass_at_true_size(eq26):
    run, k, _, true = eq26
    _, strips = rows(true, scene3d.ROD, 'LineStrips3D:strips')
    _, hub = rows(true, scene3d.HUB, 'Transform3D:quaternion')
    tip = np.array([s.reshape(-1, 3)[-1] for s in strips])
    q = np.array([r.reshape(4) for r in hub])
    theta = 2 * np.arctan2(q[:, 2], q[:, 3])
    x = tip[:, 0] * np.cos(theta) - tip[:, 1] * np.sin(theta)
    y = tip[:, 0] * np.sin(theta) + tip[:, 1] * np.cos(theta)
    _, mass = recording.read_series(true, recording.INERTIAL_TIP)
    # the recorded inertial position of the mass: (r0 + u, v) turned by theta, at z = l
    assert np.max(np.abs(x - mass[:, 0])) < 1e-6 and np.max(np.abs(y - mass[:, 1])) < 1e-6
    assert np.allclose(tip[:, 2], L) and np.allclose(mass[:, 2], L)


def test_the_drawn_rod_is_the_cantilever_from_its_root_with_the_markers_scale(eq26):
    run, k, drawn, _ = eq26
    _, strips = rows(drawn, scene3d.ROD, 'LineStrips3D:strips')
    _, mass = rows(drawn, scene3d.MASS, 'Transform3D:translation')
    _, trail = recording.read_series(drawn, scene3d.TRAIL)
    u, v, theta = run.u[k], run.v[k], run.theta[k]
    pts = np.array([s.reshape(-1, 3) for s in strips])         # (N, points, 3), rotating
    s = pts[0, :, 2] / L
    assert s == pytest.approx(np.linspace(0, 1, pts.shape[1]), abs=1e-6)
    shape = cantilever_shape(s)
    assert np.allclose(pts[:, :, 0], R0 + SCALE * u[:, None] * shape, atol=1e-6)
    assert np.allclose(pts[:, :, 1], SCALE * v[:, None] * shape, atol=1e-6)
    # the mass sits on the drawn tip; the trail is that tip in the inertial frame
    assert np.allclose(np.array([m.reshape(3) for m in mass]), pts[:, -1], atol=1e-7)
    turned = np.column_stack((pts[:, -1, 0] * np.cos(theta) - pts[:, -1, 1] * np.sin(theta),
                              pts[:, -1, 0] * np.sin(theta) + pts[:, -1, 1] * np.cos(theta)))
    assert np.allclose(trail[:, :2], turned, atol=1e-6)


def test_the_rotating_path_is_split_by_the_eq26_stages(eq26):
    run, k, drawn, _ = eq26
    t_all = run.t[k]
    seen = []
    for name, start, stop in eq26_stages(15.0, 40.0):
        t, p = recording.read_series(drawn, scene3d.path_entity(name))
        seen.append(t)
        # within its stage, to one sample at either end
        assert t.min() >= start - 0.01 - 1e-9 and t.max() <= stop + 0.01 + 1e-9, name
        i = np.round(t / 0.01).astype(int)
        assert np.allclose(p, np.column_stack((run.u[k][i], run.v[k][i])))
    both = np.sort(np.concatenate(seen))
    assert np.allclose(both, t_all)                  # every sample once
    assert '/' + scene3d.LIMIT_CIRCLE in set(recording.entity_paths(drawn))


def test_events_mark_the_stages_on_the_profiles_timeline(eq26):
    _, _, drawn, _ = eq26
    t, texts = rows(drawn, recording.EVENTS, 'TextLog:text', PROFILE_TIMELINE)
    starts = {text[0].split()[0]: tt for tt, text in zip(t, texts)}
    for name, start, _ in eq26_stages(15.0, 40.0):
        assert starts[name] == pytest.approx(start, abs=0.01 + 1e-9), name
    ts, w = recording.read_series(drawn, recording.STAGE)
    assert len(ts) == len(t) and np.all(np.abs(w) <= 2.0 + 1e-9)
    # no critical deflection event: Eq. 26 stays under 3 mm (2.79 mm at 2 rad/s)
    assert not any('critical' in text[0] for text in texts)
    assert math.isclose(Mechanism().deflection_limit, 0.003)


def test_the_usage_page_states_the_recordings_constants_as_the_code_has_them():
    from pathlib import Path

    from rotrod_core.analysis import run_events
    text = (Path(__file__).resolve().parents[3] / 'docs' / 'usage.md').read_text()
    mech = Mechanism()
    assert f'`TRAIL_SECONDS` ({scene3d.TRAIL_SECONDS:g} s)' in text
    assert f'`DWELL` ({run_events.DWELL:g} s)' in text
    assert f'`MIN_CHANGE` ({run_events.MIN_CHANGE:g} rad/s)' in text
    assert f'size ({mech.deflection_scale:g}, as the markers' in text
    assert f'(`deflection_limit`, {1e3 * mech.deflection_limit:g} mm)' in text
