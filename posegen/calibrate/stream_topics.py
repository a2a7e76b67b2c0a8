"""The topics of a recording's streams: each wrist's force/torque topic, from the config, and the joint states'."""

from __future__ import annotations

from posegen.errors import InputError
from posegen.io import check_topics
from posegen.robot import Scene


def wrench_topics(scene: Scene, measuring: bool = False) -> dict[str, str]:
    """Each chain's wrist force/torque topic, from the config.

    Args:
        scene: Scene.
        measuring: The caller measures a recording (joint speed alone is then an option, said in the error).

    Raises:
        InputError: A chain names no ``wrench_topic``.

    """
    missing = [c.name for c in scene.config.chains if not c.wrench_topic]
    if missing:
        where = ", ".join(f"chains.{name}.wrench_topic" for name in missing)
        if measuring:
            raise InputError(
                f"no wrench_topic in the config for chain(s) {', '.join(missing)} (or measure with use_wrench=False)",
                parameter="use_wrench=False",
            )
        raise InputError(
            f"no wrist force/torque topic in the config for chain(s) {', '.join(missing)}: "
            f"name it in {where} (e.g. /{missing[0]}_wrist_ft)"
        )
    return {c.name: c.wrench_topic for c in scene.config.chains}


def check_stream_topics(scene: Scene, joint_topic: str) -> dict[str, str]:
    """Each chain's wrench topic (:func:`wrench_topics`), checked with the joint states' topic: each its own.

    Raises:
        PosegenError: A chain without a wrench topic, or ``joint_topic`` no ROS 2 name or one of them.

    """
    topics = wrench_topics(scene)
    check_topics({**{f"chains.{c}.wrench_topic": t for c, t in topics.items()}, "joint_topic": joint_topic})
    return topics
