"""The messages the nodes publish: stamps, units, frames and labels."""

import math

import pytest
from geometry_msgs.msg import PointStamped, Vector3Stamped
from rclpy.serialization import deserialize_message
from rotrod_interfaces.msg import DynamicFrequencies
from sensor_msgs.msg import JointState

from rotrod_core import RodParams
from rotrod_core.estimation.whirl import Whirl, WhirlEstimate
from rotrod_core.model.equations import State
from rotrod_core.model.geometry import rod_centerline
from rotrod_ros import messages


@pytest.mark.parametrize('t', [0.0, 1.5, 1795321712.418036928, 2.9999999999])
def test_stamp_round_trip(t):
    s = messages.stamp(t)
    assert 0 <= s.nanosec < 1_000_000_000
    assert messages.to_seconds(s) == pytest.approx(t, abs=1e-9)


def test_messages_carry_units_frames_and_labels():
    t = messages.stamp(1.25)
    js = messages.joint_state(t, State(1e-3, -2e-4, 0.01, -0.02, 0.5, 2.0), -0.01, 0.3)
    assert list(js.name) == ['hub', 'tip_radial', 'tip_tangential', 'tip_pitch', 'tip_roll']
    assert list(js.position)[:3] == [0.5, 1e-3, -2e-4]
    assert list(js.velocity)[:3] == [2.0, 0.01, -0.02]
    # the tilt: the cantilever's slope 3/2 (u, v) / l, as angles about y, then -x
    su, sv = 1.5 * 1e-3 / 0.3, 1.5 * -2e-4 / 0.3
    assert js.position[3] == pytest.approx(math.atan(su), rel=1e-12)
    assert js.position[4] == pytest.approx(-math.atan2(sv, math.hypot(1, su)), rel=1e-12)
    assert js.velocity[3] == pytest.approx(1.5 * 0.01 / 0.3 / (1 + su * su), rel=1e-12)
    assert list(js.effort) == [-0.01, 0.0, 0.0, 0.0, 0.0]   # the tip joints are passive
    d = messages.deflection(t, 1e-3, -2e-4, 'rotor')
    assert d.header.frame_id == 'rotor' and (d.vector.x, d.vector.y, d.vector.z) == (
        1e-3, -2e-4, 0.0)
    f = messages.frequencies(t, 2.0, 1.6, 2.2)
    assert (f.omega, f.f1, f.f2) == (2.0, 1.6, 2.2) and f.header.stamp == t
    diag = messages.diagnostics(t, 'sim', 'hw', 1, 'warn', [('u_m', 1e-3), ('drive', 'x')])
    assert diag.status[0].level == b'\x01'
    assert [(kv.key, kv.value) for kv in diag.status[0].values] == [('u_m', '0.001'),
                                                                   ('drive', 'x')]
    # a whirl estimate: the forward whirl found, the backward one not, and why
    e = WhirlEstimate(forward=Whirl(frequency=1.6, frequency_std=1e-4),
                      backward=Whirl(frequency=math.nan, frequency_std=0.5), time=0.75,
                      window=0.99, samples=100, reason='backward: too weak')
    w = messages.whirl_estimate(messages.stamp(e.time), e)
    assert (w.f1, w.f1_std, w.f1_valid) == (1.6, 1e-4, True)
    assert math.isnan(w.f2) and math.isnan(w.f2_std) and not w.f2_valid
    assert (w.reason, w.window, w.samples) == ('backward: too weak', 0.99, 100)
    assert messages.to_seconds(w.header.stamp) == 0.75
    rod = rod_centerline(RodParams(), 1e-3, 0.0, 0.3)
    arr = messages.markers(t, 'world', 'rotrod', disk_radius=0.15, theta=0.3, rod=rod,
                           rod_diameter=0.003, mass_radius=0.02, trail=[rod[-1], rod[-1]])
    assert [m.id for m in arr.markers] == [0, 1, 2, 3, 4]
    assert all(m.header.frame_id == 'world' for m in arr.markers)


def test_marker_frames_updated_in_place_equal_fresh_arrays():
    """Frame after frame (trail growing from none, the spoke turning, the rod bending),
    the array updated in place equals one made fresh for the same shapes."""
    from rotrod_core.model.scene import scene
    frames = messages.MarkerFrames('rod1/world', 'rotrod')
    trail = []
    for k in range(6):
        theta, u = 0.4 * k, 1e-3 * (k - 2)
        rod = rod_centerline(RodParams(), u, 2e-4, theta).tolist()
        trail.append(tuple(rod[-1]))
        t = messages.stamp(0.05 * k)
        kw = dict(disk_radius=0.15 + 0.01 * (k == 4), theta=theta, rod=rod,
                  rod_diameter=0.003, mass_radius=0.02, trail=list(trail))
        updated = frames.frame(t, scene(**kw))
        fresh = messages.markers(t, 'rod1/world', 'rotrod', **kw)
        assert updated == fresh
        assert [m.id for m in updated.markers] == ([0, 1, 2, 3] if k == 0 else
                                                    [0, 1, 2, 3, 4])
        assert all(m.header.stamp == t for m in updated.markers)


def test_sample_messages_written_anew_equal_fresh_messages():
    """The node's sample messages, written sample after sample as bytes, read back as
    the fresh messages of the same values."""
    m = messages.SampleMessages('rod1/rotor', 'rod1/world')
    for k in range(3):
        t = messages.stamp(0.01 * k)
        sec, nanosec = t.sec, t.nanosec
        state = State(1e-3 * k, -2e-4, 0.01, -0.02 * k, 0.5 * k, 2.0 + k)
        assert deserialize_message(m.joint_state(sec, nanosec, state, 0.1 * k, 0.3),
                                   JointState) == messages.joint_state(t, state, 0.1 * k, 0.3)
        assert deserialize_message(m.deflection(sec, nanosec, 1e-3 * k, 2e-4),
                                   Vector3Stamped) == \
            messages.deflection(t, 1e-3 * k, 2e-4, 'rod1/rotor')
        assert deserialize_message(m.position(sec, nanosec, (0.1, 0.2 * k, 0.3)),
                                   PointStamped) == \
            messages.position(t, (0.1, 0.2 * k, 0.3), 'rod1/world')
        assert deserialize_message(m.frequencies(sec, nanosec, 0.5 * k, 1.5, 2.0 + k),
                                   DynamicFrequencies) == \
            messages.frequencies(t, 0.5 * k, 1.5, 2.0 + k)
        e = WhirlEstimate(forward=Whirl(frequency=1.5 + k, frequency_std=1e-3), time=0.5 * k,
                          window=0.99, samples=100 + k, reason='backward: weak')
        reused, fresh = messages.set_whirl_estimate(m.estimate, t, e), \
            messages.whirl_estimate(t, e)
        for name in fresh.get_fields_and_field_types():           # NaN != NaN
            a, b = getattr(reused, name), getattr(fresh, name)
            assert a == b or (a != a and b != b), name
