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


@pytest.mark.parametrize("name, method", [("tree13.xyz", "classic"), ("tree7.xyz", "classic"), ("tree1.xyz", "paths"),
                                          ("tree13.xyz", "paths")])
def test_real_scans(shared_scans, name, method):
    path = shared_scans / name
    if not path.exists(): pytest.skip(f"{path} not present")
    from treebook.pointio import read_points
    p = read_points(path)
    t = reconstruct(path, method=method)   # tree1's lowest node is one point: the root still starts under it
    one_tree(t)
    lo, hi = t.bounds()
    assert (lo >= p.min(0) - 0.5).all() and (hi <= p.max(0) + 0.5).all()  # the scan's frame and units
    assert coverage(p, tree_mesh(t, sides=12)) >= 0.85


def test_demo(tmp_path):
    from treebook.demos import demo_reconstruct
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


# --- the ground: small, sloped, rough, with outliers under it, in millimetres, or absent ---

def ground_disc(pts, n, seed=0, slope=0.0, rough=0.002, below=0, radius=0.6):
    "A ground disc of `n` points under the trunk at the origin (radius a share of the tree's width), with `below` outliers under it."
    g = np.random.default_rng(seed)
    h, r = float(np.ptp(pts[:, 2])), radius * float(np.ptp(pts[:, :2], 0).max())
    a, rr = g.uniform(0, 2 * np.pi, n), r * np.sqrt(g.uniform(0, 1, n))
    x, y = rr * np.cos(a), rr * np.sin(a)
    ground = np.column_stack([x, y, np.tan(np.radians(slope)) * x + g.normal(0, rough * h, n)])
    under = np.column_stack([g.uniform(-r, r, (below, 2)), -g.uniform(0.05, 0.3, below) * h])
    return np.vstack([ground, under])


@pytest.fixture(scope="module")
def small_scan():
    t = example_tree(levels=4, seed=3)
    assert np.allclose(t.start[0, :3], 0)  # the trunk stands on the origin
    sc = scan(t, n_points=6000, seed=1, noise=0.002, outliers=0.0)
    return t, sc.points.astype(np.float64)


@pytest.mark.parametrize("kind, kw", [("small", dict(n=4000)), ("outliers under", dict(n=6000, below=120)),
                                      ("sloped rough", dict(n=6000, slope=5, rough=0.006)), ("small disc", dict(n=1500, radius=0.15))])
def test_ground_removed(small_scan, kind, kw):
    from treebook.reconstruct import remove_ground
    _, pts = small_scan
    allp = np.vstack([pts, ground_disc(pts, **kw)])
    for scale, shift in ((1.0, 0.0), (1000.0, np.array([3.5e8, 5.7e9, 2.1e5]))):  # metres, and millimetres far from the origin
        _, gone = remove_ground(allp * scale + shift)
        assert gone[len(pts):].mean() > 0.98, kind           # the ground and what lies under it
        assert 1 - gone[:len(pts)].mean() > 0.97, kind       # the tree, all but its foot


@pytest.mark.parametrize("name", ["elm", "hickory", "shadbush", "spruce", "tulip", "vitellaria"])
def test_no_ground_keeps_the_tree(name):
    "No ground: the trunk's foot and a crown's base, level and low as they are, are not taken for it."
    from treebook.botany import grow_tree
    from treebook.reconstruct import remove_ground
    sc = scan(grow_tree(name, seed=1), n_points=6000, seed=1, noise=0.002, outliers=0.01)
    _, gone = remove_ground(sc.points.astype(np.float64))
    assert 1 - gone[~sc.outlier].mean() > 0.97


def test_real_scans_have_no_ground(shared_scans):
    from treebook.pointio import read_points
    from treebook.reconstruct import remove_ground
    paths = [p for p in sorted(shared_scans.glob("*")) if p.suffix in (".xyz", ".las")]
    if not paths: pytest.skip("no shared scans")
    for path in paths:
        assert remove_ground(read_points(path))[1].sum() == 0, path.name


def test_ground_y_up_and_reconstruct(small_scan):
    truth, pts = small_scan
    allp = np.vstack([pts, ground_disc(pts, 4000, below=80)])
    yup = np.column_stack([allp[:, 0], allp[:, 2], -allp[:, 1]])
    assert len(prepare_points(yup, up="y")) < len(pts)  # the ground went
    t = reconstruct(allp, method="classic")
    one_tree(t)
    assert np.linalg.norm(t.start[0, :3] - truth.start[0, :3]) < 0.03 * truth.size  # rooted at the true trunk base
    assert skeleton_distance(t, truth)["chamfer"] < 5
    ty = reconstruct(yup, method="classic", up="y")
    np.testing.assert_allclose(ty.bounds(), t.bounds(), atol=0.01 * truth.size)  # the same up to RANSAC on rotated floats


def test_double_surfaces_keep_the_tree():
    "A real scan three times over, two copies jittered by 0.05% of the diagonal (stations registered a few millimetres apart): the evening of `prepare_points` wins back most of what the copies cost."
    from treebook.reconstruct import SHIPPED_SCAN, _diag
    from treebook.pointio import read_points
    p = read_points(SHIPPED_SCAN)
    g = np.random.default_rng(0)
    j = 0.0005 * _diag(p)
    triple = np.vstack([p, p + g.normal(0, j, p.shape), p + g.normal(0, j, p.shape)])
    once = coverage(p, tree_mesh(reconstruct(p, method="classic"), sides=12))
    thrice = reconstruct(triple, method="classic")
    assert (thrice.parent == -1).sum() == 1
    evened = coverage(triple, tree_mesh(thrice, sides=12))
    without = coverage(triple, tree_mesh(reconstruct(triple, method="classic", voxel=0), sides=12))
    assert without < once - 0.1                     # the copies do cost
    assert once - evened < 0.5 * (once - without)   # the evening wins back more than half of it


def test_foliage_flags_and_guard(monkeypatch):
    "foliage takes True, False, 'network' or 'geometric'; when almost nothing looks like wood the leaves are kept, with a warning."
    import treebook.reconstruct as R
    p = scan(example_tree(levels=3, seed=2), n_points=3000, seed=0, noise=0.001, outliers=0.0).points.astype(np.float64)
    with pytest.raises(TreebookError, match="foliage must be"): reconstruct(p, method="classic", foliage="leaves")
    monkeypatch.setattr(R, "wood_mask", lambda q, *a, **k: np.arange(len(q)) < 50)   # 50 points of wood: too few
    with pytest.warns(UserWarning, match="the leaves were kept"):
        t, info = reconstruct(p, method="classic", foliage=True, return_info=True)
    assert (t.parent == -1).sum() == 1 and len(info["points"]) > 1000


def test_shipped_foliage_network_finds_wood():
    "On a leafy procedural scan it was not trained on, the shipped network's wood is mostly wood, and reconstruct(foliage=True) keeps it and one tree."
    from treebook.foliage import WEIGHTS as FW, foliage_scan
    from treebook.reconstruct import wood_mask
    if not FW.exists(): pytest.skip("no shipped foliage weights")
    p, wood = foliage_scan("elm", 29500)
    p = p.astype(np.float64)
    m = wood_mask(p, True)
    assert (m & wood).sum() / m.sum() > 0.7          # precision
    assert (m & wood).sum() / wood.sum() > 0.5       # recall
    t, info = reconstruct(p, method="classic", foliage=True, return_info=True)
    assert (t.parent == -1).sum() == 1 and len(info["points"]) < 0.6 * len(p)


def test_foliage_weights_given_must_exist(tmp_path):
    "Weights named but missing are an error, not a silent switch to the geometric filter."
    from treebook.reconstruct import wood_mask
    p = np.random.default_rng(0).random((600, 3))
    with pytest.raises(TreebookError, match="no foliage weights"): wood_mask(p, True, weights=tmp_path / "none.pt")
