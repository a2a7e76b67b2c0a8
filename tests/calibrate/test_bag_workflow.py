"""Which wrist topics a bag is recorded or measured with (posegen.calibrate.bag_workflow)."""

from pathlib import Path

import pytest

from posegen.calibrate.bag_workflow import wrench_topics
from posegen.errors import InputError
from posegen.robot import Scene, load_config

CONFIGS = Path(__file__).resolve().parents[2] / "configs"


def test_the_configs_topics_are_returned_per_chain():
    scene = Scene(load_config(CONFIGS / "talos_table.yaml"))
    topics = wrench_topics(scene)
    assert set(topics) == {c.name for c in scene.config.chains}
    assert all(topic.startswith("/") for topic in topics.values())


def test_a_recording_without_topics_names_the_config_key_not_a_measure_option():
    scene = Scene(load_config(CONFIGS / "icub_table.yaml"))  # names no wrist topic
    with pytest.raises(InputError, match=r"chains\.\w+\.wrench_topic") as recording:
        wrench_topics(scene)
    assert "use_wrench" not in str(recording.value) and recording.value.parameter is None
    with pytest.raises(InputError, match="use_wrench=False") as measuring:
        wrench_topics(scene, measuring=True)
    assert measuring.value.parameter == "use_wrench=False"
