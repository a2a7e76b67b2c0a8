"""The YAML text of a drafted config, commented where the user has to look."""

from __future__ import annotations

import dataclasses
from typing import Any

import yaml

from posegen.errors import ConfigError
from posegen.io import check_apart, claim_output, write_atomic
from posegen.robot.additions import Capsule, DisabledPair
from posegen.robot.collision_matrix import PairSurvey, survey_scene_pairs
from posegen.robot.config import load_config, parse_config
from posegen.robot.draft import Draft, draft_robot
from posegen.robot.scene import Scene
from posegen.robot.validation import check_for_planning


def _flow(value: Any) -> str:
    """One YAML value on one line (flow style)."""
    return str(yaml.safe_dump(value, default_flow_style=True, width=10_000)).strip().removesuffix("...").strip()


def pairs_text(pairs: tuple[DisabledPair, ...], indent: str = "    ") -> list[str]:
    """``disabled_pairs:`` lines, one pair per line."""
    lines = [f"{indent}disabled_pairs:                  # never checked: adjacent, touching at rest, always touching"]
    lines += [f"{indent}  - {_flow([p.link_a, p.link_b, p.reason.value])}" for p in pairs]
    return lines


def render_draft(draft: Draft, seed: int) -> str:
    """The config text of a draft, ready to edit."""
    lines = [
        f"# posegen scene: {draft.robot} at a table (drafted by `posegen robot init {draft.robot}`).",
        "# Every value below was found from the robot description by heuristics: check each one,",
        "# in particular the lines marked EDIT. Units: m, rad (angles in *_deg keys are degrees).",
        "robot:",
        "  source:",
        f"    example_robot_data: {draft.robot}",
    ]
    if draft.srdf:
        lines.append(f"    srdf: {draft.srdf}")
    lines.append("  locked_joints:                     # held fixed (rad): off the legs and arms (head, fingers)")
    lines += [f"    {name}: {value:.4g}" for name, value in draft.locked.items()]
    lines.append("  frames:                            # EDIT: where the hands touch the table (declared here)")
    for chain in draft.chains:
        for frame in chain.touch:
            lines.append(f"    {frame.name}: {{parent: {frame.parent}, xyz_m: {_flow(list(frame.xyz_m))}}}")
    if draft.velocity_limits:
        lines.append("  velocity_limits_rad_s:             # EDIT: the URDF gives none or an implausible one")
        for name, value in draft.velocity_limits.items():
            lines.append(f"    {name}: {value}    # URDF: {draft.urdf_velocity[name]:g} rad/s")
    lines.append("  collision:")
    lines += pairs_text(draft.survey.disabled)
    lines.append(
        f"    # found on {draft.survey.samples} random postures (seed {seed}), "
        f"{len(draft.survey.disabled)} of {draft.survey.pairs_surveyed} link pairs"
    )
    if draft.shapes:
        lines.append("    shapes:                          # EDIT: these links' meshes miss their centre of mass")
        for link, gap in draft.misplaced.items():
            lines.append(f"      {link}:                    # CoM {1e3 * gap:.0f} mm outside its collision geometry")
            for shape in draft.shapes:
                if isinstance(shape, Capsule) and shape.link == link:
                    entry = {"from_m": list(shape.from_m), "to_m": list(shape.to_m), "radius_m": shape.radius_m}
                    lines.append(f"        - capsule: {_flow(entry)}")
    left, right = draft.chains
    lines += [
        "",
        "stance:",
        f"  reference_posture: {draft.reference_posture or '~'}"
        + ("      # the SRDF's first group state" if draft.reference_posture else "      # every joint at 0"),
        f"  sole_frames: {_flow(list(draft.soles))}   # the first one anchors the floating base",
        f"  foot_x_m: {_flow(list(draft.foot_x_m))}   # sole rectangle in the sole frame (lowest foot vertices)",
        f"  foot_y_m: {_flow(list(draft.foot_y_m))}",
        f"  floor_contact_frames: {_flow(list(draft.floor_contact))}   # links that may touch the floor",
        "",
        "chains:",
    ]
    half = 0.1 * (draft.spots_y_m[-1] - draft.spots_y_m[0])
    ranges = {
        "left": [round(-half, 3), round(draft.spots_y_m[-1], 3)],
        "right": [round(draft.spots_y_m[0], 3), round(half, 3)],
    }
    for chain in (left, right):
        lines += [
            f"  {chain.name}:                            # arm: {', '.join(chain.joints)}",
            f"    sole_frame: {chain.sole}",
            f"    gripper_frame: {chain.hand}",
            f"    fingertip_frames: {_flow([f.name for f in chain.touch])}   # EDIT (see robot.frames)",
            "    fingertip_length_m: 0.0",
            f"    contact_frame: {chain.name}_contact",
            f"    spot_y_range_m: {_flow(ranges[chain.name])}",
        ]
    lines += [
        "",
        f"table:                               # from the arm's reach ({draft.reach_m:.2f} m, shoulder to hand)",
        f"  top_center_m: {_flow(list(draft.table_center_m))}",
        "  yaw_deg: 0.0",
        f"  size_m: {_flow(list(draft.table_size_m))}",
        f"  spots_x_m: {_flow(list(draft.spots_x_m))}",
        f"  spots_y_m: {_flow(list(draft.spots_y_m))}",
        f"  approach_standoff_m: {round(0.06 * draft.reach_m / 0.9, 3)}",
        "",
        "margins: {com_m: 0.02, collision_m: 0.005, joint_limit_rad: 0.02}",
        "sampling: {soft_iterations: 50, hard_iterations: 15, "
        f"spot_tolerance_m: {round(0.06 * draft.reach_m / 0.9, 3)}, chunk_size: 32}}",
        "",
    ]
    return "\n".join(lines)


def write_draft(robot: str, output: str, srdf: str | None = None, samples: int = 400, seed: int = 0) -> Draft:
    """Draft a config for an example-robot-data robot and write it (atomically) to ``output``.

    The draft is re-read as a config before it is written; whether it already loads as a
    scene (names, balance, reach) is added to its notes.

    Raises:
        ConfigError: Unknown robot, or a structure that is not two legs and two arms.
        OutputError: ``output`` cannot be written, or another posegen is writing it.

    """
    check_apart([output], [srdf])  # never over the SRDF it reads
    with claim_output(output):  # checked and locked before any work
        draft = draft_robot(robot, srdf, samples, seed)
        text = render_draft(draft, seed)
        config = parse_config(yaml.safe_load(text), output)
        try:
            check_for_planning(Scene(config))
            verdict = "the draft loads as a scene (names, soles, balance, reach checked)"
        except ConfigError as exc:
            verdict = f"the draft does not load yet: {exc}"
        write_atomic(output, text)
    return dataclasses.replace(draft, notes=(*draft.notes, verdict))


def survey_config_pairs(config_path: str, samples: int = 400, seed: int = 0) -> tuple[PairSurvey, str]:
    """Re-find the collision pairs to disable for a config, and the block to paste into it.

    For after editing a config's locked joints, reference posture or collision shapes.
    """
    survey = survey_scene_pairs(Scene(load_config(config_path)), samples, seed)
    return survey, "\n".join(pairs_text(survey.disabled))
