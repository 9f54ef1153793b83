"""Property tests of the Tree type (hypothesis): file round trips, parent inference, traversal orders."""
import numpy as np
from hypothesis import given, settings, strategies as st

from treebook.tree import Tree


@st.composite
def trees(draw, max_n=40):
    "A random valid tree: a random parent list (parents first), positions from a seeded random walk."
    n = draw(st.integers(1, max_n))
    roots_ok = draw(st.booleans())  # sometimes a forest of several roots
    parent = [-1] + [draw(st.integers(-1 if roots_ok else 0, i - 1)) for i in range(1, n)]
    rng = np.random.default_rng(draw(st.integers(0, 2**32 - 1)))
    start, end = np.zeros((n, 4)), np.zeros((n, 4))
    for i, p in enumerate(parent):
        start[i, :3] = end[p, :3] if p >= 0 else rng.uniform(-10, 10, 3)
        end[i, :3] = start[i, :3] + rng.normal(size=3) * rng.uniform(0.1, 2)
    start[:, 3], end[:, 3] = rng.uniform(0, 0.5, n), rng.uniform(0, 0.5, n)
    extra = {"stage": rng.integers(0, 10, n)} if draw(st.booleans()) else {}
    return Tree(start, end, parent, **extra)


@settings(max_examples=60, deadline=None)
@given(trees(), st.sampled_from(["npz", "json"]))
def test_save_load_round_trip_is_exact(tmp_path_factory, tree, ext):
    path = tmp_path_factory.mktemp("rt") / f"t.{ext}"
    tree.save(path)
    back = Tree.load(path)
    assert back == tree
    assert back.start.tobytes() == tree.start.tobytes() and back.end.tobytes() == tree.end.tobytes()


@settings(max_examples=80, deadline=None)
@given(trees())
def test_from_segments_recovers_parents(tree):
    assert Tree.from_segments(tree.start, tree.end).parent.tolist() == tree.parent.tolist()


@settings(max_examples=80, deadline=None)
@given(trees(), st.sampled_from(["dfs", "bfs"]))
def test_orders_visit_every_branch_once_parents_first(tree, kind):
    order = tree.order(kind)
    assert sorted(order.tolist()) == list(range(tree.n))
    pos = np.empty(tree.n, int); pos[order] = np.arange(tree.n)
    child = tree.parent >= 0
    assert np.all(pos[tree.parent[child]] < pos[child])
    # re-storing in that order and taking any prefix gives valid trees
    re = tree.reorder(kind)
    assert re.n == tree.n
    k = max(1, tree.n // 2)
    assert tree.prefix(k, kind).n == k


@settings(max_examples=40, deadline=None)
@given(trees(), st.floats(-np.pi, np.pi))
def test_normalize_restore_round_trip(tree, angle):
    t = tree.rotate_z(angle)
    canon, frame = t.normalize()
    back = frame.restore(canon)
    assert np.allclose(back.start, t.start, atol=1e-4 * max(t.size, 1))
