import pytest

from posegen.errors import ArgumentError
from posegen.io import check_topics, topic_name_problem


@pytest.mark.parametrize("name", ["/joint_states", "/a/b_2/_c", "/joint_trajectory_controller/joint_trajectory"])
def test_fully_qualified_names_pass(name):
    assert topic_name_problem(name) is None


@pytest.mark.parametrize(
    ("name", "says"),
    [
        ("", "expected a ROS 2 topic name"),
        (None, "expected a ROS 2 topic name"),
        ("joint_states", "starts with '/'"),
        ("/", "none empty"),
        ("/a//b", "none empty"),
        ("/a/", "none empty"),
        ("/a/2b", "starting with a digit"),
        ("/a b", "letters, digits and '_'"),
        ("/a-b", "letters, digits and '_'"),
        ("/~/a", "letters, digits and '_'"),
    ],
)
def test_a_name_ros_2_refuses_is_refused_with_its_reason(name, says):
    problem = topic_name_problem(name)
    assert problem is not None and says in problem


def test_two_streams_on_one_topic_name_the_later_parameter():
    with pytest.raises(ArgumentError, match=r"segments_topic: '/x' is already in use \(by topic\)") as caught:
        check_topics({"topic": "/x", "segments_topic": "/x"})
    assert caught.value.parameter == "segments_topic"
    with pytest.raises(ArgumentError, match=r"joint_topic: a ROS 2 topic name starts with '/'") as caught:
        check_topics({"chains.left.wrench_topic": "/l", "joint_topic": "joint_states"})
    assert caught.value.parameter == "joint_topic"
    check_topics({"topic": "/x", "segments_topic": "/y"})  # distinct valid names pass
