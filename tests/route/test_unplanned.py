"""A planning failure is a typed result; its words are those route files have always recorded."""

import pickle

from posegen.route import Unplanned, UnplannedCause


def test_the_words_a_route_file_records_are_unchanged():
    stop = Unplanned(UnplannedCause.NO_VERTICAL)
    assert str(stop) == "no balanced, collision-free vertical approach above the contact"
    blocked = Unplanned(
        UnplannedCause.NO_FREE_MOTION,
        "straight line and 3 via sequences blocked, OMPL found no checked path in 2000 nor 8000 state checks",
    )
    assert str(blocked) == (
        "no free motion: straight line and 3 via sequences blocked, "
        "OMPL found no checked path in 2000 nor 8000 state checks"
    )


def test_a_failure_crosses_to_the_process_that_routes():
    blocked = Unplanned(UnplannedCause.NO_FREE_MOTION, "tried")
    back = pickle.loads(pickle.dumps(blocked))
    assert back == blocked and back.cause is UnplannedCause.NO_FREE_MOTION
