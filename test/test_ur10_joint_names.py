"""The joint names a UR10 command may carry: bare or with the arm's prefix, whatever the arm
is called (ur10_conversions.joint_order, what the simulator reads commands with)."""
import pytest

from leap_teleop.ros.ur10_conversions import ARM_JOINTS, GRIPPER_JOINTS, CommandError, joint_order
from leap_teleop.ur10.config import ARM_NAME


@pytest.mark.parametrize('arm, expected', [
    ('ur10_1', ARM_JOINTS), ('wrist', ARM_JOINTS), ('shoulder', ARM_JOINTS), ('finger', GRIPPER_JOINTS)])
def test_bare_and_prefixed_names_are_taken_whatever_the_arm_is_called(arm, expected):
    # An arm named 'wrist' had its prefix stripped from the bare 'wrist_1_joint' ('1_joint'):
    # a client sending bare names had every command refused.
    assert ARM_NAME.fullmatch(arm)                  # a name the cell config accepts
    prefix = arm + '_'
    names = list(reversed(expected))
    want = list(range(len(names)))[::-1]
    assert joint_order(names, expected, prefix) == want
    assert joint_order([prefix + n for n in names], expected, prefix) == want
    mixed = [n if i % 2 else prefix + n for i, n in enumerate(names)]
    assert joint_order(mixed, expected, prefix) == want


@pytest.mark.parametrize('arm, names, why', [
    ('wrist', ['wrist_1_joint', 'wrist_wrist_1_joint'], "joint 'wrist_wrist_1_joint' given twice"),
    ('wrist', ['1_joint'], "unknown joint '1_joint'"),
    ('finger', ['finger_finger_joint', 'finger_joint'], "joint 'finger_joint' given twice"),
    ('finger', ['finger_elbow_joint'], "unknown joint 'finger_elbow_joint'"),
])
def test_a_joint_given_twice_or_unknown_is_still_refused(arm, names, why):
    expected = GRIPPER_JOINTS if arm == 'finger' else ARM_JOINTS
    with pytest.raises(CommandError, match=why):
        joint_order(names, expected, arm + '_')
