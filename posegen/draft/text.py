"""The YAML text of a drafted config, commented where the user has to look."""

from __future__ import annotations

import contextlib
import dataclasses
from pathlib import Path
from typing import Any

import yaml

from posegen.draft.drafting import Draft, draft_robot
from posegen.draft.limits import COM_MARGIN_M
from posegen.draft.mjcf_source import converted_urdf, mjcf_files, mjcf_source, urdf_beside
from posegen.draft.source import source_files
from posegen.errors import ConfigError, InfeasibleError
from posegen.io import check_apart, check_named, claim_output, write_atomic
from posegen.model import pool_size
from posegen.robot import (
    Box,
    Capsule,
    CollisionChecker,
    DisabledPair,
    PairSurvey,
    Scene,
    VisualHull,
    check_for_planning,
    check_reference_limits,
    load_config,
    parse_config,
    survey_scene_pairs,
)

POINT_CONE_DEG = 60.0  # a drafted point contact: the hand may tilt this far from the table's normal


def _flow(value: Any) -> str:
    """One YAML value on one line (flow style); a name YAML would read otherwise (``no``, ``a: #1``) is quoted."""
    return str(yaml.safe_dump(value, default_flow_style=True, width=10_000)).strip().removesuffix("...").strip()


def pairs_text(pairs: tuple[DisabledPair, ...], indent: str = "    ") -> list[str]:
    """``disabled_pairs:`` lines, one pair per line."""
    lines = [f"{indent}disabled_pairs:                  # never checked: adjacent, touching at rest, always touching"]
    lines += [f"{indent}  - {_flow([p.link_a, p.link_b, p.reason.value])}" for p in pairs]
    return lines


def render_draft(draft: Draft, seed: int, command: str = "") -> str:
    """The config text of a draft, ready to edit: every guess has a ``# CHECK:`` line."""
    made = command or f"posegen robot init {draft.robot}"
    lines = [
        f"# posegen scene: {Path(draft.robot).stem} at a table (drafted by `{made}`).",
        "# Every value below was found from the robot description by heuristics. The `# CHECK:` lines say",
        "# what was guessed and how to check it. Units: m, rad (angles in *_deg keys are degrees).",
        *[f"# CHECK: {check}" for check in draft.checks],
        "robot:",
        "  source:",
    ]
    source = draft.source
    if source.example_robot_data:
        lines.append(f"    example_robot_data: {_flow(source.example_robot_data)}")
    else:
        lines.append(f"    urdf: {_flow(source.urdf)}")
    if source.srdf:
        lines.append(f"    srdf: {_flow(source.srdf)}")
    if source.package_dirs:
        lines.append(f"    package_dirs: {_flow(list(source.package_dirs))}")
    if draft.locked:
        lines.append("  locked_joints:                     # held fixed (rad): off the legs and arms (head, fingers)")
        lines += [f"    {_flow(name)}: {_exact(value)}" for name, value in draft.locked.items()]
    lines.append("  frames:                            # declared here, added to the description at load")
    for frame in draft.frames:
        entry = f"{{parent: {_flow(frame.parent)}, xyz_m: {_flow(list(frame.xyz_m))}"
        if any(frame.rpy_deg):
            entry += f", rpy_deg: {_flow(list(frame.rpy_deg))}"
        lines.append(f"    {_flow(frame.name)}: {entry}}}")
    if draft.velocity_limits:
        lines.append("  velocity_limits_rad_s:             # CHECK: the URDF gives none or an implausible one")
        for name, value in draft.velocity_limits.items():
            lines.append(f"    {_flow(name)}: {value}    # URDF: {draft.urdf_velocity[name]:g} rad/s")
    lines.append("  collision:")
    lines += pairs_text(draft.survey.disabled)
    lines.append(
        f"    # found on {draft.survey.samples} random postures (seed {seed}), "
        f"{len(draft.survey.disabled)} of {draft.survey.pairs_surveyed} link pairs"
    )
    if draft.shapes:
        lines += _shapes_text(draft)
    lines += _stance_text(draft)
    lines += _chains_text(draft)
    half_standoff = round(0.06 * draft.reach_m / 0.9, 3)
    lines += [
        "",
        f"table:                               # CHECK: from the arm's reach ({draft.reach_m:.2f} m, shoulder to hand)",
        f"  top_center_m: {_flow(list(draft.table_center_m))}",
        f"  yaw_deg: {draft.table_yaw_deg}",
        f"  size_m: {_flow(list(draft.table_size_m))}",
        f"  spots_x_m: {_flow(list(draft.spots_x_m))}",
        f"  spots_y_m: {_flow(list(draft.spots_y_m))}",
        f"  approach_standoff_m: {half_standoff}",
        "",
        f"margins: {{com_m: {COM_MARGIN_M}, collision_m: 0.005, joint_limit_rad: {draft.joint_limit_margin_rad}}}",
        f"sampling: {{soft_iterations: 50, hard_iterations: 15, spot_tolerance_m: {half_standoff}, chunk_size: 32}}",
        "",
    ]
    return "\n".join(lines + _press_text(draft))


def _exact(value: float) -> str:
    """A locked angle (rad) written short when 4 digits hold it, else in full (a zero-width range's own limit)."""
    short = f"{value:.4g}"
    return short if float(short) == value else repr(float(value))


def _press_text(draft: Draft) -> list[str]:
    """A lighter press than posegen's default, found at half that force by ``measure`` (none: the default)."""
    if draft.contact_force_n is None:
        return []
    return [
        f"route: {{contact_force_n: {draft.contact_force_n:g}}}   # CHECK: what the wrists hold",
        f"recording: {{force_threshold_n: {draft.contact_force_n / 2:g}}}   # half the contact force",
        "",
    ]


def _shapes_text(draft: Draft) -> list[str]:
    lines = ["    shapes:                          # CHECK: links without collision geometry, or with wrong geometry"]
    for link in dict.fromkeys(shape.link for shape in draft.shapes):
        if link in draft.misplaced:
            why = f"its collision geometry: {draft.misplaced[link]}"
        elif link in draft.left_out:
            why = f"its collision shapes: {draft.left_out[link]}"
        else:
            why = f"no collision geometry: {draft.covered.get(link, '')}"
        lines.append(f"      {_flow(link)}:                    # {why}")
        for shape in draft.shapes:
            if shape.link != link:
                continue
            if isinstance(shape, Capsule):
                entry = {"from_m": list(shape.from_m), "to_m": list(shape.to_m), "radius_m": shape.radius_m}
                lines.append(f"        - capsule: {_flow(entry)}")
            elif isinstance(shape, VisualHull):
                lines.append("        - visual_hull: {}")
            elif isinstance(shape, Box):
                entry = {"center_m": list(shape.center_m), "size_m": list(shape.size_m), "rpy_deg": list(shape.rpy_deg)}
                lines.append(f"        - box: {_flow(entry)}")
    return lines


def _stance_text(draft: Draft) -> list[str]:
    left, right = draft.soles
    lines = ["", "stance:"]
    if draft.reference_posture:
        lines.append(f"  reference_posture: {_flow(draft.reference_posture)}      # the SRDF's first group state")
    if draft.root_rpy_deg is not None:
        lines.append(f"  root_rpy_deg: {_flow(list(draft.root_rpy_deg))}   # the model's {draft.up_axis} axis up")
    if draft.reference_joints:
        lines.append(
            "  reference_joints:                  # CHECK: set by the draft (legs bent, joints off their limits)"
        )
        lines += [f"    {_flow(name)}: {value}" for name, value in draft.reference_joints.items()]
    guessed = "" if left.from_geometry and right.from_geometry else "   # CHECK: no foot geometry: a guess"
    lines += [
        f"  sole_frames: {_flow([left.frame, right.frame])}   # the first one anchors the floating base",
        f"  foot_x_m: {_flow(list(draft.foot_x_m))}   # sole rectangle in the sole frame{guessed}",
        f"  foot_y_m: {_flow(list(draft.foot_y_m))}",
        f"  floor_contact_frames: {_flow(list(draft.floor_contact))}   # links that may touch the floor",
    ]
    return lines


def _chains_text(draft: Draft) -> list[str]:
    half = 0.1 * (draft.spots_y_m[-1] - draft.spots_y_m[0])
    ranges = {
        "left": [round(-half, 3), round(draft.spots_y_m[-1], 3)],
        "right": [round(draft.spots_y_m[0], 3), round(half, 3)],
    }
    lines = ["", "chains:"]
    for chain in draft.chains:
        contact = chain.contact
        lines += [
            f"  {chain.name}:                            # arm: {', '.join(chain.joints)}",
            f"    sole_frame: {_flow(chain.sole)}",
            f"    gripper_frame: {_flow(chain.gripper.name)}   # on {chain.hand}, the arm's last link",
        ]
        if contact.flush:
            lines += [
                f"    fingertip_frames: {_flow([f.name for f in contact.frames])}   # CHECK: {contact.how}",
                "    fingertip_length_m: 0.0",
            ]
            if contact.touching:
                lines.append(
                    f"    touching_links: {_flow(list(contact.touching))}   # the links fixed to the hand whose "
                    "geometry makes the face"
                )
        else:
            lines += [
                "    fingertip_frames: []",
                "    contact_kind: point",
                f"    point_frame: {_flow(contact.frames[0].name)}   # CHECK: {contact.how}",
                f"    point_radius_m: {contact.radius_m}",
                f"    point_cone_deg: {POINT_CONE_DEG}   # CHECK: how far the hand may tilt from the table's normal",
            ]
            if contact.touching:
                lines.append(
                    f"    touching_links: {_flow(list(contact.touching))}   # CHECK: the locked fingers beside the tip "
                    "may touch the table too"
                )
        lines += [f"    contact_frame: {chain.name}_contact", f"    spot_y_range_m: {_flow(ranges[chain.name])}"]
    return lines


def write_draft(
    robot: str,
    output: str,
    srdf: str | None = None,
    samples: int = 400,
    seed: int = 0,
    package_dirs: tuple[str, ...] = (),
    command: str = "",
) -> Draft:
    """Draft a config for a robot (example-robot-data name, URDF or MJCF file) and write it (atomically) to ``output``.

    An MJCF model is converted to a URDF written beside the draft (``<output stem>.urdf``,
    :mod:`posegen.draft.mjcf_source`), which the draft names and the stages read.

    The draft is re-read as a config before it is written; whether it already loads as a
    scene (names, balance, reach, collisions at the reference) is added to its notes.

    Raises:
        ConfigError: Unknown robot, a description that does not load, or a structure that
            is not two legs and two arms.
        OutputError: ``output`` cannot be written, or another posegen is writing it; it (or
            the converted URDF) is a file the draft reads (the description, its SRDF, a
            mesh); the converted URDF's place holds another file.

    """
    mjcf = mjcf_source(robot)
    check_named(output)
    urdf = urdf_beside(output) if mjcf else None
    read = mjcf_files(mjcf) if mjcf else source_files(robot, srdf, package_dirs)
    check_apart([output, urdf], [srdf, *read])  # never over the description, its SRDF or a mesh it reads
    with claim_output(output, beside=[urdf] if urdf else []), contextlib.ExitStack() as stack:
        if mjcf is None:
            draft = draft_robot(robot, srdf, samples, seed, package_dirs)
        else:  # the URDF converted beside the draft, removed if drafting fails
            converted = stack.enter_context(converted_urdf(mjcf, output))
            draft = draft_robot(str(converted.urdf), srdf, samples, seed, package_dirs)
            draft = dataclasses.replace(
                draft, robot=robot, checks=(converted.check, *draft.checks), notes=(converted.note, *draft.notes)
            )
        text = render_draft(draft, seed, command)
        config = parse_config(yaml.safe_load(text), output)
        try:
            scene = Scene(config)
            check_for_planning(scene, CollisionChecker(scene))
            verdicts: tuple[str, ...] = (
                pool_size(scene).describe(),
                "the draft loads as a scene (names, soles, balance, reach, collisions at the reference checked)",
            )  # the verdict last
        except (ConfigError, InfeasibleError) as exc:
            verdicts = (f"the draft does not load yet: {exc}",)
        write_atomic(output, text)
    return dataclasses.replace(draft, notes=(*draft.notes, *verdicts))


def survey_config_pairs(config_path: str, samples: int = 400, seed: int = 0) -> tuple[PairSurvey, str]:
    """Re-find the collision pairs to disable for a config, and the block to paste into it.

    For after editing a config's locked joints, reference posture or collision shapes.

    Raises:
        ConfigError: The config does not load, or its reference posture is not inside the joint limits.

    """
    scene = Scene(load_config(config_path))
    check_reference_limits(scene)  # the pairs that touch at rest are found about the reference
    survey = survey_scene_pairs(scene, samples, seed)
    return survey, "\n".join(pairs_text(survey.disabled))
