"Reconstruction from scans: bad inputs end in a clear TreebookError or a sensible tree; real scans give one connected tree."
import numpy as np
import pytest

from treebook.tree import Tree, TreebookError, example_tree
from treebook.scan import scan
from treebook.mesh import tree_mesh
from treebook.partnet import WEIGHTS
from treebook.reconstruct import reconstruct, coverage, skeleton_distance, prepare_points

METHODS = ["classic"] + (["partnet"] if WEIGHTS.exists() else [])


@pytest.fixture(scope="module")
def tree_scan():
    t = example_tree(levels=4, seed=3)
    return t, scan(t, n_points=8000, seed=1, noise=0.002, outliers=0.01).points


def one_tree(t: Tree):
    assert isinstance(t, Tree) and t.n >= 1
    assert int((t.parent == -1).sum()) == 1
    assert np.isfinite(t.start).all() and (t.start[:, 3] > 0).all()


@pytest.mark.parametrize("method", METHODS)
def test_procedural_scan(tree_scan, method):
    truth, pts = tree_scan
    t = reconstruct(pts, method=method, seed=0)
    one_tree(t)
    assert skeleton_distance(t, truth)["chamfer"] < 5  # % of the diagonal


@pytest.mark.parametrize("bad, msg", [
    (np.zeros((0, 3)), "empty"),
    (np.zeros((1, 3)), "only 1 points"),
    (np.array([[0, 0, np.nan]] * 50), "NaN"),
    (np.column_stack([np.random.default_rng(0).uniform(size=(500, 2)), np.zeros(500)]), "lie on a plane"),
    (np.ones((100, 3)), "identical"),
])
def test_bad_arrays(bad, msg):
    with pytest.raises(TreebookError, match=msg): reconstruct(bad, method="classic")


def test_bad_files(tmp_path):
    (tmp_path / "empty.xyz").write_text("")
    with pytest.raises(TreebookError, match="empty"): reconstruct(tmp_path / "empty.xyz", method="classic")
    (tmp_path / "one.xyz").write_text("1 2 3\n")
    with pytest.raises(TreebookError, match="only 1 points"): reconstruct(tmp_path / "one.xyz", method="classic")
    with pytest.raises(TreebookError, match="no such file"): reconstruct(tmp_path / "missing.xyz", method="classic")
    with pytest.raises(TreebookError, match="method"): reconstruct(np.ones((20, 3)), method="nope")
    with pytest.raises(TreebookError, match="`up`"): reconstruct(np.ones((20, 3)), method="classic", up="x")


def test_ground_plane_and_outliers(tree_scan):
    truth, pts = tree_scan
    rng = np.random.default_rng(0)
    lo, hi = pts.min(0), pts.max(0)
    ground = np.column_stack([rng.uniform(lo[0] - 1, hi[0] + 1, 6000), rng.uniform(lo[1] - 1, hi[1] + 1, 6000), rng.normal(lo[2], 0.002, 6000)])
    out = rng.uniform(lo - 0.5, hi + 0.5, (200, 3))
    t = reconstruct(np.vstack([pts, ground, out]), method="classic")
    one_tree(t)
    assert skeleton_distance(t, truth)["chamfer"] < 5
    assert len(prepare_points(np.vstack([pts, ground]))) < len(pts) + 500


def test_y_up(tree_scan):
    _, pts = tree_scan
    z = reconstruct(pts, method="classic")
    y = reconstruct(np.column_stack([pts[:, 0], pts[:, 2], -pts[:, 1]]), method="classic", up="y")
    np.testing.assert_allclose(y.bounds(), z.bounds(), atol=1e-3)


def test_million_points(tree_scan):
    _, pts = tree_scan
    rng = np.random.default_rng(0)
    big = np.repeat(pts, 125, axis=0) + rng.normal(0, 0.002, (len(pts) * 125, 3))
    assert len(big) == 1_000_000
    t, info = reconstruct(big, method="classic", max_points=20_000, return_info=True)
    one_tree(t)
    lab = info["labels_full"]  # one segment per input point, in full resolution
    assert lab.shape == (1_000_000,) and lab.max() < t.n
    assert (lab >= 0).mean() > 0.95


@pytest.mark.parametrize("name", ["tree13.xyz", "tree7.xyz"])
def test_real_scans(shared_scans, name):
    path = shared_scans / name
    if not path.exists(): pytest.skip(f"{path} not present")
    from treebook.pointio import read_points
    p = read_points(path)
    t = reconstruct(path, method="classic")
    one_tree(t)
    lo, hi = t.bounds()
    assert (lo >= p.min(0) - 0.5).all() and (hi <= p.max(0) + 0.5).all()  # the scan's frame and units
    assert coverage(p, tree_mesh(t, sides=12)) >= 0.85


def test_demo(tmp_path):
    from treebook.reconstruct import demo_reconstruct
    paths = demo_reconstruct(tmp_path, method="classic")
    assert all(p.exists() and p.stat().st_size > 0 for p in paths)
    one_tree(Tree.load(paths[0]))


def test_hermite_switch(tree_scan):
    from treebook.reconstruct import _turns
    _, pts = tree_scan
    plain = reconstruct(pts, method="classic", hermite=False)
    joined = reconstruct(pts, method="classic")
    one_tree(joined)
    assert (_turns(joined) > 120).sum() <= (_turns(plain) > 120).sum()
    np.testing.assert_allclose(joined.bounds(), plain.bounds(), atol=0.05 * plain.size)
