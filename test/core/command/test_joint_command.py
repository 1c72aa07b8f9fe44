"""Reading the hub's command from joint_command messages: sensor_msgs/JointState's
contract (each field empty or one entry per name), as topic_based_ros2_control's
TopicBasedSystem keeps it for a <ros2_control> block of the hub alone."""

import math

import pytest

from rotrod_core.command.joint_command import MalformedJointCommand, hub_command

TIP = ['tip_radial', 'tip_tangential']


def test_a_block_of_the_hub_alone_sends_one_entry_per_field():
    assert hub_command(['hub'], [], [1.5], [], 'velocity') == ('omega', 1.5)
    assert hub_command(['hub'], [], [], [-0.02], 'torque') == ('torque', -0.02)


@pytest.mark.parametrize('names', [['hub', 'x'], ['hub', *TIP], [*TIP, 'hub'],
                                   ['tip_radial', 'hub', 'tip_tangential']])
def test_fewer_entries_than_names_are_refused_whichever_joint_they_might_be(names):
    # the example: name [hub, x], velocity [3.0]; the lengths differ, which
    # sensor_msgs/JointState forbids: whose entry 3.0 is would be a guess
    for drive, fields in (('velocity', ([], [3.0], [])), ('torque', ([], [], [0.1]))):
        with pytest.raises(MalformedJointCommand, match=r'has 1 entries for \d joint names'):
            hub_command(names, *fields, drive)


def test_one_entry_per_name_is_read_by_name_and_other_joints_are_ignored():
    names = ['tip_radial', 'hub', 'tip_tangential', 'arm']
    assert hub_command(names, [], [9.0, 2.0, 8.0, math.nan], [], 'velocity') == ('omega', 2.0)
    assert hub_command(names, [], [], [7.0, 0.5, 6.0, 5.0], 'torque') == ('torque', 0.5)


def test_a_hub_with_both_command_interfaces_gives_the_active_drives_field():
    names = ['hub', *TIP]
    assert hub_command(names, [], [1.0, 0, 0], [0.3, 0, 0], 'velocity') == ('omega', 1.0)
    assert hub_command(names, [], [1.0, 0, 0], [0.3, 0, 0], 'torque') == ('torque', 0.3)


@pytest.mark.parametrize('names, position, velocity, effort, drive, reason', [
    (TIP, [], [1.0, 1.0], [], 'velocity', "no joint 'hub' in the names"),
    ([], [], [], [], 'velocity', "no joint 'hub' in the names (got none)"),
    (['hub', 'hub'], [], [1.0, 1.0], [], 'velocity', "joint 'hub' is named 2 times"),
    (['hub'], [], [1.0, 2.0], [], 'velocity', 'velocity has 2 entries for 1 joint names'),
    (['hub', *TIP], [], [1.0, 2.0], [], 'velocity', 'velocity has 2 entries for 3 joint'),
    (TIP, [], [1.0], [], 'velocity', 'velocity has 1 entries for 2 joint names'),
    (['hub'], [0.0, 1.0], [1.0], [], 'velocity', 'position has 2 entries for 1 joint'),
    (['hub'], [], [math.nan], [], 'velocity', "velocity of joint 'hub' is nan"),
    (['hub'], [], [math.inf], [], 'velocity', 'must be finite'),
    (['hub'], [], [], [-math.inf], 'torque', "effort of joint 'hub' is -inf"),
    (['hub'], [], [1.0], [math.nan], 'velocity', "effort of joint 'hub' is nan"),
    (['hub', *TIP], [], [], [0.1, 0.0, 0.0], 'velocity',
     "effort for joint 'hub' ignored: drive is 'velocity' (set drive to 'torque'"),
    (['hub'], [], [1.0], [], 'torque',
     "velocity for joint 'hub' ignored: drive is 'torque' (set drive to 'velocity'"),
    (['hub'], [0.5], [], [], 'velocity', 'position commands'),
    (['hub'], [], [], [], 'torque', "no effort for joint 'hub' (drive 'torque')"),
])
def test_malformed_messages_are_refused_with_the_reason(names, position, velocity, effort,
                                                        drive, reason):
    with pytest.raises(MalformedJointCommand) as err:
        hub_command(names, position, velocity, effort, drive)
    assert reason in str(err.value)


def test_an_unknown_drive_is_a_programming_error():
    with pytest.raises(ValueError, match='drive must be one of'):
        hub_command(['hub'], [], [1.0], [], 'position')
