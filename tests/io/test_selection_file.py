"""The selection file as an object: what ``select`` returns is what it wrote, read back to the byte."""

import pytest
import yaml

from posegen.errors import InputError
from posegen.io import load_postures, write_yaml
from posegen.select import (
    DesignFigures,
    FollowUpFigures,
    Selection,
    SelectionMethod,
    SessionFigures,
    chosen_from_pool,
    read_selection,
    select_pool_file,
    write_selection,
)
from tests.conftest import EXAMPLE_POOL


def test_the_selection_returned_is_the_file_written_and_reads_back_to_the_same_bytes(tmp_path, example_pool):
    path = tmp_path / "selected.yaml"
    returned = select_pool_file(str(EXAMPLE_POOL), str(path))
    found = read_selection(path)
    assert found == returned and found.method == SelectionMethod.IROC
    assert isinstance(found.figures, DesignFigures)
    assert found.figures.selected == len(found.postures) == found.figures.iroc.selected_k
    assert found.figures.detmax.runs == 0 and found.figures.detmax.best_o1 is None
    raw = yaml.safe_load(path.read_text())
    assert raw["figures"]["certificate"]["kiefer_wolfowitz_gap"] == found.figures.certificate.kiefer_wolfowitz_gap
    for chosen in found.postures:  # each posture is its pool row's
        assert chosen.posture == example_pool.postures[chosen.pool_id]
    assert [c.rank for c in found.postures] == sorted(c.rank for c in found.postures)  # IROC's top k, in order
    write_selection(tmp_path / "again.yaml", found)
    assert (tmp_path / "again.yaml").read_bytes() == path.read_bytes()
    plan, _ = load_postures(path)  # the stages read it as postures
    assert plan.postures == tuple(c.posture for c in found.postures)


def test_follow_up_and_session_selections_round_trip(tmp_path, example_pool):
    follow = FollowUpFigures(
        selected=2,
        pool_postures=len(example_pool.postures),
        given_contacts=40,
        excluded_postures=None,
        candidate="offsets",
        prior_scale=5.0,
        weakest_chain="right",
        weakest_from="given",
        predicted_height_sigma_mm={"left": (1.5, 1.25), "right": (2.0, 1.0)},
    )
    postures = (chosen_from_pool(example_pool, 7, 1, 0.5), chosen_from_pool(example_pool, 3, 2, 0.25))
    provenance = dict(example_pool.provenance)
    followed = Selection(provenance, SelectionMethod.FOLLOWUP, example_pool.joint_names, follow, postures)
    again = (chosen_from_pool(example_pool, 11, 0, 0.0),)
    session = Selection(
        provenance, SelectionMethod.SESSION, example_pool.joint_names, SessionFigures((11,), follow), again + postures
    )
    alone = Selection(provenance, SelectionMethod.SESSION, example_pool.joint_names, SessionFigures((11,), None), again)
    for name, selection in (("followup", followed), ("session", session), ("missing", alone)):
        path = tmp_path / f"{name}.yaml"
        write_selection(path, selection)
        assert read_selection(path) == selection, name
        raw = yaml.safe_load(path.read_text())
        assert "excluded_postures" not in str(raw["figures"])  # written only when given
        assert [p["id"] for p in raw["postures"]] == [c.pool_id for c in selection.postures]


@pytest.mark.parametrize(
    ("edit", "message"),
    [
        (lambda d: d.pop("figures"), "not a posegen selection"),
        (lambda d: d.update(method="best"), "not a posegen selection"),
        (lambda d: d["figures"].pop("certificate"), "not a posegen selection"),
        (lambda d: d.update(format_version=2), "unsupported format_version"),
        (lambda d: d["postures"][0].pop("rank"), "posture 0: 'rank' must be an integer, got None"),
        (lambda d: d["postures"][0].update(rank=float("nan")), "posture 0: 'rank' must be an integer, got nan"),
        (lambda d: d["postures"][0].update(rank="3"), "posture 0: 'rank' must be an integer, got '3'"),
        (lambda d: d["postures"][2].update(pool_id=True), "posture 2: 'pool_id' must be an integer, got True"),
        (lambda d: d["postures"][0].update(weight=float("inf")), "posture 0: 'weight' must be a finite number"),
        (lambda d: d["postures"][1].pop("joints"), "posture 1: malformed"),
        # a helper's faults that route, simulate and check took
        (lambda d: d["postures"][0].update(pool_id=99999), r"posture 0: pool_id 99999 is not a row of its pool"),
        (lambda d: d["postures"][0].update(pool_id=-1), r"posture 0: pool_id -1 is not a row of its pool"),
        (lambda d: d["postures"][0].update(weight=-0.5), "posture 0: 'weight' -0.5 is negative"),
    ],
)
def test_a_malformed_selection_is_refused_in_one_line(tmp_path, selection_file, edit, message):
    """By both readers: read_selection, and load_postures (the stages': route, simulate, calibrate)."""
    data = yaml.safe_load(selection_file.read_text())
    edit(data)
    write_yaml(tmp_path / "bad.yaml", data)
    for read in (read_selection, load_postures):
        with pytest.raises(InputError, match=message) as refused:
            read(tmp_path / "bad.yaml")
        assert "\n" not in str(refused.value)


def test_a_pool_is_not_a_selection(tmp_path):
    with pytest.raises(InputError, match="posegen-selection"):
        read_selection(EXAMPLE_POOL)
