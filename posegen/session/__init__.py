"""An experiment that knows when it is done: ``posegen session``, batch by batch until the error meets the target.

Above the four stages (it chains them): the first batch identifies every base
parameter (select's exact k), each batch is routed, checked and exported as a rosbag2;
a recorded batch is measured and calibrated on every contact so far, and the
calibration's grouped-CV predicted held-out error per chain either meets the target
(done) or the next batch is chosen for the weakest chain (``select --given``). A
rehearsal plays the batches on a simulated robot.

Internal: scripts use the public API at ``posegen.`` (stable, documented with examples); the
names here are its plumbing and may change between versions.
"""

from posegen.session.batch import missing_rows, route_pool_rows
from posegen.session.index import (
    INDEX_FILE,
    SESSION_FORMAT,
    SESSION_VERSION,
    Assessment,
    Batch,
    BatchState,
    Deliverable,
    Recording,
    SessionIndex,
    SessionSettings,
    write_index,
)
from posegen.session.index_reader import read_index
from posegen.session.rehearsal import REHEARSAL_BAG, Robot, rehearse_session
from posegen.session.status import STATUS_PLOT, Status, session_status
from posegen.session.workflow import Added, Report, add_bag, open_session, start_session

__all__ = [
    "INDEX_FILE",
    "REHEARSAL_BAG",
    "SESSION_FORMAT",
    "SESSION_VERSION",
    "STATUS_PLOT",
    "Added",
    "Assessment",
    "Batch",
    "BatchState",
    "Deliverable",
    "Recording",
    "Report",
    "Robot",
    "SessionIndex",
    "SessionSettings",
    "Status",
    "add_bag",
    "missing_rows",
    "open_session",
    "read_index",
    "rehearse_session",
    "route_pool_rows",
    "session_status",
    "start_session",
    "write_index",
]
