"""One foot-to-hand chain of a config, and the contacts its hand makes (flush or point)."""

from __future__ import annotations

from dataclasses import dataclass, fields

from posegen.errors import ConfigError
from posegen.io import topic_name_problem
from posegen.robot.config_reader import Reader
from posegen.robot.contact_kinds import DEFAULT_KIND, ContactKind, kind_named, registered_kinds


@dataclass(frozen=True)
class ChainConfig:
    """One foot-to-hand chain (one arm) and the contacts its hand makes.

    A flush contact needs ``fingertip_frames``: posegen adds ``contact_frame`` at their
    ends' centroid. A point contact needs ``point_frame``: a frame at the centre of the
    touching tip's rounding, z pointing away from the table at a contact. A chain may
    declare both (its sessions may mix kinds); ``contact_kind`` is the one ``pool`` plans.
    """

    name: str
    sole_frame: str
    gripper_frame: str  # the link the contact points are rigidly attached to
    fingertip_frames: tuple[str, ...]
    fingertip_length_m: float  # from a fingertip link origin to its end, along -z of gripper_frame
    contact_frame: str  # name given to the flush contact frame that posegen adds to the model
    spot_y_range_m: tuple[float, float]  # table-frame y range of the spots this arm serves
    recorded_as: str = ""  # the name recordings give this gripper (e.g. "robot/gripper_a")
    wrench_topic: str = ""  # rosbag2 topic of this wrist's force/torque sensor (geometry_msgs/WrenchStamped)
    contact_kind: ContactKind = DEFAULT_KIND  # what `pool` plans
    point_frame: str = ""  # the point contact's frame ("": no point contact)
    point_radius_m: float = 0.0  # the tip's rounding: its centre stays this far above the table
    point_cone_deg: float = 30.0  # largest tilt of the point frame's z from the table normal
    touching_links: tuple[str, ...] = ()  # links that may touch the table too at this chain's contact (fingers)
    wrench_frame: str = ""  # the wrist force/torque sensor's frame, its wrench expressed in it ("": gripper_frame)
    tool_mass_kg: float | None = None  # what the sensor carries (None: fitted from each recording by measure)
    tool_com_m: tuple[float, float, float] | None = None  # its CoM in the sensor frame (with tool_mass_kg)

    @property
    def sensor_frame(self) -> str:
        """The frame the wrist's force/torque sensor measures in (``wrench_frame``, else ``gripper_frame``)."""
        return self.wrench_frame or self.gripper_frame

    def frame(self, kind: ContactKind) -> str:
        """The frame whose pose a contact of this kind constrains."""
        return kind.frame(self)

    @property
    def kinds(self) -> tuple[ContactKind, ...]:
        """The registered contact kinds this chain declares."""
        return tuple(kind for kind in registered_kinds() if kind.declared(self))


CHAIN_DEFAULTS = {
    "contact_kind": DEFAULT_KIND.value,
    "point_frame": "",
    "point_radius_m": 0.0,
    "point_cone_deg": 30.0,
    "touching_links": (),
}


MAX_FINGERTIP_M = 0.3  # m: a fingertip link's origin to its end (TALOS: 0.03); longer is no fingertip


def _point(ch: Reader, key: str) -> tuple[float, float, float] | None:
    if ch.raw(key, None) is None:
        return None
    x, y, z = ch.numbers(key, 3)
    return (x, y, z)


def read_chain(ch: Reader, name: str) -> ChainConfig:
    """One chain: its frames, the contacts its hand makes, the spots it serves.

    Raises:
        ConfigError: An unknown key, a malformed field or a fingertip frame listed twice.

    """
    ch.keys_within(tuple(f.name for f in fields(ChainConfig) if f.name != "name"))
    try:
        kind = kind_named(ch.text("contact_kind", DEFAULT_KIND.value))
    except ValueError as exc:
        raise ConfigError(f"chains.{name}.contact_kind: {exc}") from exc
    point = ch.text("point_frame", "") if "point_frame" in ch.data else ""
    tips = ch.texts("fingertip_frames", [])
    if len(set(tips)) != len(tips):
        raise ConfigError(f"chains.{name}.fingertip_frames: a frame is listed twice: {list(tips)}")
    cone = ch.number("point_cone_deg", 30.0, minimum=0.0)
    chain = ChainConfig(
        name=name,
        sole_frame=ch.text("sole_frame"),
        gripper_frame=ch.text("gripper_frame"),
        fingertip_frames=tips,
        fingertip_length_m=ch.number("fingertip_length_m", 0.0, minimum=0.0, maximum=MAX_FINGERTIP_M),
        contact_frame=ch.text("contact_frame") if tips else str(ch.raw("contact_frame", "") or ""),
        spot_y_range_m=ch.interval("spot_y_range_m"),
        recorded_as=ch.text("recorded_as", name),
        wrench_topic=ch.text("wrench_topic") if ch.raw("wrench_topic", "") else "",
        contact_kind=kind,
        point_frame=point,
        point_radius_m=ch.number("point_radius_m", 0.0, minimum=0.0),
        point_cone_deg=cone,
        touching_links=ch.texts("touching_links", []),
        wrench_frame=ch.text("wrench_frame") if ch.raw("wrench_frame", "") else "",
        tool_mass_kg=ch.number("tool_mass_kg", minimum=0.0) if ch.raw("tool_mass_kg", None) is not None else None,
        tool_com_m=_point(ch, "tool_com_m"),
    )
    problem = topic_name_problem(chain.wrench_topic) if chain.wrench_topic else None
    if problem is not None:
        raise ConfigError(f"chains.{name}.wrench_topic: {problem}")
    if (chain.tool_mass_kg is None) != (chain.tool_com_m is None):
        raise ConfigError(f"chains.{name}: give tool_mass_kg and tool_com_m together (or neither: measure fits them)")
    for each in registered_kinds():
        each.check(chain, planned=each == kind)
    return chain


def require_distinct(chains: tuple[ChainConfig, ...]) -> None:
    """No two chains share a frame posegen adds, a recording's name or a wrench topic.

    Raises:
        ConfigError: Two do (named by the later chain's field).

    """
    for field in ("contact_frame", "recorded_as", "wrench_topic"):
        seen: dict[str, str] = {}
        for chain in chains:
            value = getattr(chain, field)
            if value and value in seen:
                owner = seen[value]
                raise ConfigError(f"chains.{chain.name}.{field}: '{value}' is chains.{owner}'s too; give each its own")
            seen[value] = chain.name
