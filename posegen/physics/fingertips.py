"""A hand settling flush on its fingertips: their polygon, whether each carries load, the turn that loads them.

A hand with fingertips meets the table turned by up to 5 deg from where the nominal model
puts it (the arm's and the legs' errors); pressed down, it rests on two of its tips, its
contact frame tilted 1-2 deg on average against the table. A flush contact pins that
frame's roll and pitch at zero, so a calibration reads the tilt as the kinematics'. The
wrist's force/torque sensor tells it: the centre of pressure of the table's push, carried
to the contact frame, lies on the fingertips' polygon's edge. Turning the hand about its
contact origin by the roll and pitch torque there brings the centre of pressure inside,
every tip loaded (:func:`flush_turn`).
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from posegen.physics.geometry import tip_points
from posegen.physics.shaping import bounded_rate
from posegen.physics.stabilizer import Hull
from posegen.robot import FloatArray, Scene, centre_of_pressure

K_FLUSH = 0.15  # rad/s per N m of roll or pitch torque about the contact origin, while a tip carries no load
FLUSH_MARGIN_M = 0.005  # the centre of pressure this far inside the fingertips' polygon: every tip carries load
MAX_FLUSH_TILT_RAD = 0.1  # a hand turns at most this far from the plan to settle flush
TORQUE_FILTER_S = 0.02  # low-pass of the roll and pitch torques a hand settles flush by (the sensor's noise)


def tip_polygon(scene: Scene, chain: str) -> Hull | None:
    """The polygon (m, contact frame x and y) of a chain's fingertip ends; None for a point contact.

    Example:
        >>> tip_polygon(scene, "left").margin(np.zeros(2))  # TALOS: the contact origin 2 cm inside
        0.0203...

    """
    spec = scene.chain(chain)
    if not spec.fingertip_frames:
        return None
    model = scene.model
    data = model.createData()
    pin.framesForwardKinematics(model, data, scene.model_configuration(scene.locked_values))
    contact = data.oMf[scene.frame_id(spec.frame(spec.contact_kind))]
    ends = [contact.actInv(data.oMf[scene.frame_id(tip)].act(point))[:2] for tip, point, _ in tip_points(scene, chain)]
    return Hull.of(np.array(ends))


def loads_every_tip(polygon: Hull, force_n: float, torque_nm: FloatArray) -> bool:
    """Whether a push loads every fingertip: its centre of pressure ``FLUSH_MARGIN_M`` inside their polygon.

    ``force_n`` (N, > 0) the push along the contact normal, ``torque_nm`` (2,) its roll and pitch
    torques about the contact origin (the contact frame's x and y).

    Example:
        >>> loads_every_tip(tip_polygon(scene, "left"), 30.0, np.zeros(2))  # pressed at the origin
        True

    """
    return polygon.margin(centre_of_pressure(force_n, torque_nm)) >= FLUSH_MARGIN_M


def flush_turn(torque_nm: FloatArray, tilt_rad: FloatArray, max_rate_rad_s: float) -> FloatArray:
    """The roll and pitch rates (2,) rad/s that unload the edge a hand rests on, no further than its bound.

    ``torque_nm`` (2,) the roll and pitch torques about the contact origin (world axes), ``tilt_rad``
    (2,) how far the hand has turned from its plan already (``MAX_FLUSH_TILT_RAD`` at most),
    ``max_rate_rad_s`` the hand's fastest turn.

    Example:
        >>> flush_turn(np.array([0.4, -0.2]), np.zeros(2), 0.2)  # K_FLUSH x the torque
        array([ 0.06, -0.03])

    """
    return bounded_rate(K_FLUSH * np.asarray(torque_nm, dtype=float), max_rate_rad_s, tilt_rad, MAX_FLUSH_TILT_RAD)
