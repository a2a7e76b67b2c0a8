"""A session played on a simulated robot, batch after batch, until it is done (``posegen session rehearse``).

Each batch's route is run by the perturbed robot of ``posegen simulate ROUTE --bag``
(drawn with every chain of the config: the same robot for every batch,
:func:`posegen.calibrate.simulate_route_bag`);
its recording, ``batch_NNN/rehearsal_bag`` (its true parameters beside it), is added as a
real one would be.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from posegen.arguments import check_count, check_seed
from posegen.calibrate import simulate_route_bag
from posegen.io import OutputKind, RecordedBag, claim_output
from posegen.parallel import Backend
from posegen.session.batch import ROUTE_FILE
from posegen.session.index import BatchState, SessionIndex
from posegen.session.workflow import CONFIG_FILE, Added, Report, add_recorded, open_session

REHEARSAL_BAG = "rehearsal_bag"
RATE_HZ = 500.0  # of the simulated joint states and wrenches (simulate --bag's default)
CONTACT_NOISE_MM = 3.0  # the real recordings' contact noise as calibrate reports it (3.1 mm / 0.30 / 0.35 deg)
CONTACT_NOISE_DEG = 0.3


@dataclass(frozen=True)
class Robot:
    """The simulated robot a rehearsal plays on (as ``posegen simulate``'s options).

    Its contact noise is by default as large as the real recordings' (the table, the
    fingertips and the force control, not only the encoders).
    """

    seed: int = 0
    compliance_rad_per_knm: float = 0.0
    error_mm: float = 2.0
    error_deg: float = 0.5
    noise_deg: float = 0.005
    contact_noise_mm: float = CONTACT_NOISE_MM
    contact_noise_deg: float = CONTACT_NOISE_DEG


def rehearse_session(
    session: str,
    robot: Robot,
    backend: Backend,
    max_batches: int = 20,
    told: Callable[[Added], None] = lambda added: None,
    report: Report | None = None,
) -> list[Added]:
    """Play the session's batches on a simulated robot until it ends (done, at its floor) or ``max_batches`` are added.

    The session's lock is held for the whole rehearsal: an ``add`` or another rehearsal
    started meanwhile fails at once, naming this one.

    Args:
        session: Session folder (started; it may be partly played: it resumes).
        robot: The simulated robot.
        backend: Where routing, checking and cross-validation run.
        max_batches: Batches to add at most in this call.
        told: Called after each batch is added.
        report: Writes each calibration's report into its staging folder (see :func:`add_bag`).

    Raises:
        PosegenError: Not a session, a file edited by hand, or a step that fails.

    """
    check_seed(robot.seed, "seed")
    check_count(max_batches, "max_batches")
    folder = Path(session)
    added: list[Added] = []
    index = open_session(folder)  # not a session: said before the lock
    with claim_output(folder, OutputKind.FOLDER):  # for the whole rehearsal: no add runs meanwhile
        index = open_session(folder)
        while not index.ended and len(added) < max_batches:
            last = index.batches[-1]
            bag = folder / last.folder / REHEARSAL_BAG
            if last.state is BatchState.PLANNED:
                _play(folder, index, robot, bag)
            recorded = RecordedBag(bag)
            result = add_recorded(folder, recorded, recorded.sha256(), backend, False, report)
            added.append(result)
            told(result)
            index = result.index
    return added


def _play(folder: Path, index: SessionIndex, robot: Robot, bag: Path) -> None:
    """The last batch's route run by the simulated robot, recorded at ``bag``."""
    last = index.batches[-1]
    simulate_route_bag(
        str(folder / last.folder / ROUTE_FILE),
        str(bag),
        config_path=str(folder / CONFIG_FILE),
        seed=robot.seed,
        error_mm=robot.error_mm,
        error_deg=robot.error_deg,
        noise_deg=robot.noise_deg,
        session=index.table,
        rate_hz=RATE_HZ,
        joint_topic=index.settings.joint_topic,
        compliance_rad_per_knm=robot.compliance_rad_per_knm,
        every_chain=True,  # the same robot for every batch, whichever chains it touches with
        contact_noise_mm=robot.contact_noise_mm,
        contact_noise_deg=robot.contact_noise_deg,
    )
