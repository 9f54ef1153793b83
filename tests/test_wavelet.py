"""Wavelet shape grammar (notebook 08, 08a, 08b): transform, rules, MSTs, propagation and bad inputs."""
from pathlib import Path

import numpy as np
import pytest
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

from treebook.tree import Tree, TreebookError
from treebook.pointio import read_points
from treebook.lsystem import Grammar, mst_tree, productions
from treebook.wavelet import (_infer, align, compression, dyad, enhance, infer_grammar, inverse, propagate, pyramid,
                              shipped_scan, super_resolve, transform, voxel_rules, voxelize)

SCANS = Path(__file__).resolve().parent.parent.parent / "shared" / "data" / "scans"


@pytest.fixture(scope="module")
def inferred():
    return _infer(shipped_scan(), 64)


def test_transform_round_trip_exact():
    rng = np.random.default_rng(0)
    occ = rng.random((32, 32, 32)) < 0.05
    co = transform(occ)
    rec = inverse(co)
    assert np.abs(rec - occ).max() < 1e-5
    assert np.array_equal(rec > 0.5, occ)
    assert [dyad(co, j).shape for j in range(5)] == [(2 ** j,) * 3 for j in range(5)]


def test_compression_all_ones():
    row = compression(np.ones((8, 8, 8), bool))
    assert row["nonzero"] == 1 and row["lossy_iou"] == 1.0 and row["lossless"] == pytest.approx(1 - 1 / 512)


def test_voxel_rule_extraction_hand_built():
    line = np.zeros((8, 8, 8), bool)
    line[2, 4, :] = True
    cnt = voxel_rules(line, transitions=1)
    mid = (1 << 4) | (1 << 5)                      # neighbours below and above
    assert np.flatnonzero(cnt[mid]).tolist() == [0b11] and cnt[mid].sum() == 2
    assert np.array_equal(super_resolve(pyramid(line)[2], cnt, seed=3), line)


def test_production_extraction_hand_built():
    coarse = Tree([[0, 0, 0, 0]], [[0, 0, 2, 0]], [-1])
    fine = Tree([[0, 0, 0, 0], [0, 0, 1, 0], [0, 0, 1, 0]], [[0, 0, 1, 0], [0, 0, 2, 0], [0.7, 0, 1.7, 0]], [-1, 0, 0])
    pr = productions(coarse, fine, h=1.0)
    assert pr["ptr"].tolist() == [0, 3]
    np.testing.assert_allclose(pr["offset"], [[0, 0, 0], [1, 0, 0], [1, 0, 0]], atol=1e-6)
    np.testing.assert_allclose(pr["vector"][:2], [[1, 0, 0], [1, 0, 0]], atol=1e-6)


@pytest.mark.parametrize("text,msg", [("", "empty"), ("0 0 0\n1 1 1\n", "only 2 points"), ("1 2 3\n" * 20, "identical"),
                                      ("1 2 nan\n" + "0 0 1\n" * 3 + "".join(f"{i} {i} {i}\n" for i in range(20)), "NaN")])
def test_bad_files(tmp_path, text, msg):
    f = tmp_path / "scan.xyz"
    f.write_text(text)
    with pytest.raises(TreebookError, match=msg):
        infer_grammar(f)


def test_bad_grid_and_flags(tmp_path):
    pts = read_points(shipped_scan())
    for bad in (4, 0, 100, 48):
        with pytest.raises(TreebookError, match="power of two"):
            infer_grammar(pts, grid=bad)
    with pytest.raises(TreebookError, match="`up` must be"):
        infer_grammar(pts, up="x")
    with pytest.raises(TreebookError, match="no such file"):
        infer_grammar(tmp_path / "missing.xyz")
    with pytest.raises(TreebookError, match="n must be"):
        propagate(infer_grammar(pts, grid=64), n=0)


def test_mst_one_connected_tree_per_dyad(inferred):
    g, trees, vox, co = inferred
    assert len(trees) >= 4
    for j, t in trees.items():
        assert (t.parent < np.arange(t.n)).all()
        m = t.n + 1                                  # nodes = branch ends + the root
        pts = np.concatenate([t.start[t.roots[:1], :3], t.end[:, :3]])
        ends = np.arange(1, m)
        src = np.where(t.parent >= 0, t.parent + 1, 0)
        ncomp, _ = connected_components(coo_matrix((np.ones(t.n), (src, ends)), shape=(m, m)), directed=False)
        assert ncomp == 1, f"dyad {j} is not one tree"
        assert np.allclose(t.start[t.roots, :3], pts[0])


def test_mst_joins_components():
    p = np.concatenate([np.column_stack([np.zeros(10), np.zeros(10), np.arange(10.0)]), [[50, 50, 50.0], [51, 50, 50]]])
    t = mst_tree(p, k=2)
    assert t.n == 11 and len(t.roots) == 1


def test_propagated_trees_differ_and_keep_height(inferred):
    g, trees, vox, co = inferred
    ref = trees[g.finest]
    forest = propagate(g, n=4, seed=0)
    for t in forest:
        assert abs(t.height - ref.height) <= 0.2 * ref.height
        assert t.n != ref.n or not np.allclose(t.end[:, :3], ref.end[:, :3])
    for a in range(len(forest)):
        for b in range(a + 1, len(forest)):
            fa, fb = forest[a], forest[b]
            assert fa.n != fb.n or not np.allclose(fa.end[:, :3], fb.end[:, :3])
    again = propagate(g, n=2, seed=0)
    assert np.allclose(again[0].end, forest[0].end)


def test_grammar_json_round_trip(tmp_path, inferred):
    g = inferred[0]
    g2 = Grammar.load(g.save(tmp_path / "g.json"))
    assert g2.n_rules == g.n_rules and g2.levels == g.levels
    assert g.turtle(0).count("[") == g.turtle(0).count("]")
    (tmp_path / "bad.json").write_text("[1, 2]")
    with pytest.raises(TreebookError, match="not a treebook grammar"):
        Grammar.load(tmp_path / "bad.json")


def test_enhance_adds_detail():
    t = enhance(shipped_scan(), levels=1, grid=64, seed=0)
    g, trees, _, _ = _infer(shipped_scan(), 64, compress=False)
    assert t.n > trees[g.finest].n
    assert abs(t.height - trees[g.finest].height) <= 0.2 * trees[g.finest].height


@pytest.mark.skipif(not SCANS.exists(), reason="shared scans not present")
@pytest.mark.parametrize("name", ["tree1.xyz", "tree7.xyz", "tree13.xyz", "pytlidar_tree_1.las"])
def test_every_shared_scan(name):
    g = infer_grammar(SCANS / name, grid=64)
    assert g.n_rules > 10
    for t in propagate(g, n=2, seed=1):
        assert t.n > 10


def test_simplify_turns_staircase_into_limb():
    from treebook.lsystem import simplify
    stair = np.array([[0, 0, 0], [0, 0, 1], [1, 0, 1], [1, 0, 2], [2, 0, 2], [2, 0, 3], [3, 0, 3], [3, 0, 4], [4, 0, 4], [1, 1, 1]], float)
    q, par = simplify(stair, np.array([-1, 0, 1, 2, 3, 4, 5, 6, 7, 2]), h=1.0)
    assert len(q) < 5 and par[0] == -1 and (par[1:] < np.arange(1, len(q))).all()
    np.testing.assert_allclose(q[[0, -1]], [[0, 0, 0], [4, 0, 4]])


@pytest.mark.skipif(not SCANS.exists(), reason="shared scans not present")
def test_propagated_trees_are_siblings_of_the_scan():
    """Chamfer (normalised by height): propagated trees are much nearer the scan than other scans are, yet differ from each other."""
    from treebook.lsystem import chamfer
    g, trees, _, _ = _infer(shipped_scan(), 128, compress=False)
    ref = trees[g.finest]
    forest = propagate(g, n=3, seed=0)
    others = []
    for name in ["tree1.xyz", "tree7.xyz", "pytlidar_tree_1.las"]:
        _, tr, _, _ = _infer(SCANS / name, 128, compress=False)
        others.append(chamfer(ref, tr[max(tr)]))
    prop = [chamfer(ref, t) for t in forest]
    assert max(prop) < 0.8 * min(others), (prop, others)
    assert min(chamfer(forest[i], forest[j]) for i in range(3) for j in range(i + 1, 3)) > 0.01
    for t in forest:
        assert abs(t.height - ref.height) <= 0.2 * ref.height
    enh = enhance(shipped_scan(), levels=1, grid=128, seed=0)
    assert chamfer(ref, enh) < 0.5 * min(prop)
