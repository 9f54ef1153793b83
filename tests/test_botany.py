"The acceptance checks of issue 3: many grown trees are valid, capped, contain their earlier stages; datasets hold them."
import numpy as np
import pytest

from treebook.botany import SPECIES, grow, grow_tree, tree_stats, stage_tree
from treebook.datasets import generate_dataset, load_trees
from treebook.tree import Tree

COUNTS = {name: (100 if name == "elm" else 20) for name in SPECIES}


@pytest.mark.parametrize("name", list(SPECIES))
def test_stages_contain_each_other(name):
    cap = SPECIES[name].max_branches
    for seed in range(COUNTS[name]):
        hist = grow(name, seed=seed, stages=10)
        assert len(hist) == 10
        for a, b in zip(hist, hist[1:]):
            assert a.n <= b.n
            np.testing.assert_array_equal(b.start[:a.n, :3], a.start[:, :3])
            np.testing.assert_array_equal(b.end[:a.n, :3], a.end[:, :3])
            np.testing.assert_array_equal(b.parent[:a.n], a.parent)
            assert (b.start[:a.n, 3] >= a.start[:, 3]).all() and (b.end[:a.n, 3] >= a.end[:, 3]).all()
        final = hist[-1]
        assert 2 <= final.n <= cap
        Tree(final.start, final.end, final.parent, stage=final.stage)  # passes every check again
        st = stage_tree(final, 5)
        np.testing.assert_allclose(st.start, hist[5].start, rtol=1e-5, atol=1e-7)
        np.testing.assert_allclose(st.end, hist[5].end, rtol=1e-5, atol=1e-7)
        np.testing.assert_array_equal(st.parent, hist[5].parent)


def test_generate_all_species(tmp_path):
    for name, n in COUNTS.items():
        m = generate_dataset(name, n, tmp_path / name, stages=10, workers=2, shard_size=25, progress=False)
        assert m["complete"] and m["counts"]["trees"] == n
        trees = load_trees(tmp_path / name)
        assert len(trees) == n and all(2 <= t.n <= SPECIES[name].max_branches for t in trees)
        assert all(t.stage.max() <= 9 and (np.diff(t.stage) >= 0).all() for t in trees)


def test_species_differ():
    def stats(name): return [tree_stats(grow_tree(name, seed=s)) for s in range(10)]
    hw = {name: np.array([s["height_width"] for s in stats(name)]) for name in SPECIES}
    assert hw["spruce"].mean() > 2 * hw["elm"].mean()
    assert hw["spruce"].min() > hw["elm"].max()          # the distributions do not even overlap
    assert hw["vitellaria"].mean() < hw["hickory"].mean()
    ang = {name: np.mean([s["branch_angle"] for s in stats(name)]) for name in ("spruce", "elm")}
    assert ang["spruce"] > ang["elm"] + 15                # spruce laterals leave near-horizontally
