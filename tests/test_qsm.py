"""Tree measurements (`treebook.qsm`): truth on a procedural tree, and bad input with one-line errors."""
import numpy as np
import pytest

from treebook.qsm import (CYLINDER_COLUMNS, example_in_metres, qsm, read_cylinders, segment_volumes,
                          trunk_radius_at, write_qsm)
from treebook.scan import scan
from treebook.tree import TreebookError


@pytest.fixture(scope="module")
def measured():
    truth = example_in_metres()
    pts = scan(truth, n_points=30000, views=3, noise=0.0003, outliers=0.0, sides=24, seed=1).points.astype(float)
    return truth, pts, qsm(pts)


def test_close_to_the_truth(measured):
    truth, _, m = measured
    s = m.summary
    assert abs(s["dbh"] / (2 * trunk_radius_at(truth, 1.3)) - 1) < 0.05
    assert abs(s["total_volume"] / segment_volumes(truth).sum() - 1) < 0.15
    assert abs(s["total_length"] / truth.lengths.sum() - 1) < 0.15
    assert abs(s["height"] - 8.0) < 0.2


def test_tables_add_up(measured, tmp_path):
    _, _, m = measured
    cyl, br, s = m.cylinders, m.branches, m.summary
    assert np.isclose(cyl["length"].sum(), s["total_length"]) and np.isclose(br["volume"].sum(), s["total_volume"])
    assert s["trunk_volume"] + s["branch_volume"] == pytest.approx(s["total_volume"])
    assert (cyl["branch_order"][cyl["branch"] == 1] == 0).all() and cyl["parent"][0] == 0
    rows = np.arange(1, len(cyl["radius"]) + 1)
    assert set(cyl["parent"][1:]) <= set(rows) and set(cyl["extension"]) - {0} <= set(rows)
    back = read_cylinders(write_qsm(m, tmp_path, "t")[0])
    assert list(back) == list(CYLINDER_COLUMNS) and np.allclose(back["start_z"], cyl["start_z"], atol=1e-5)


def test_a_tree_too_short_for_dbh(measured):
    truth, pts, _ = measured
    with pytest.raises(TreebookError, match="needs a taller tree"):
        qsm(pts * 0.1)   # 80 cm tall


@pytest.mark.parametrize("bad, message", [
    (np.zeros((0, 3)), "empty|no points|points"),
    (np.full((500, 3), np.nan), "NaN|finite|not a number"),
    (np.ones((1, 3)), "point"),
])
def test_bad_points(bad, message):
    with pytest.raises(TreebookError, match=message):
        qsm(bad)


def test_bad_files(tmp_path):
    (tmp_path / "empty.xyz").write_text("")
    with pytest.raises(TreebookError):
        qsm(tmp_path / "empty.xyz")
    with pytest.raises(TreebookError):
        qsm(tmp_path / "missing.xyz")
    (tmp_path / "notes.csv").write_text("a,b\n1,2\n")
    with pytest.raises(TreebookError, match="not a cylinder table"):
        read_cylinders(tmp_path / "notes.csv")
