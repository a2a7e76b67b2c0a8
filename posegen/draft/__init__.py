"""Stage 0: a robot's config drafted from its description (``posegen robot init``, ``robot pairs``).

A URDF or MJCF model (or an example-robot-data name) read for structure, never names: its
legs and soles, arms and hands, a bent stance, collision geometry for the links that move,
joint limits, a table within the arms' reach, the collision pairs to disable; every guess
written as a ``# CHECK:`` line of the config it drafts. The stages then read that config
through :mod:`posegen.robot`, as they read a shipped one.

Internal: scripts use the public API at ``posegen.`` (stable, documented with examples); the
names here are its plumbing and may change between versions.
"""

from posegen.draft.drafting import Draft, draft_robot
from posegen.draft.mjcf import convert_mjcf, is_mjcf
from posegen.draft.text import survey_config_pairs, write_draft

__all__ = ["Draft", "convert_mjcf", "draft_robot", "is_mjcf", "survey_config_pairs", "write_draft"]
