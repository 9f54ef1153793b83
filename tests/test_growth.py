"""Growth, completion, conditions and widgets: prompts kept exactly, stage sequences, sketch files, points frames, headless sliders."""
import json
from pathlib import Path

import numpy as np
import pytest
import torch

from treebook.tree import Tree, TreebookError
from treebook.botany import grow
from treebook.tokens import STAGE, Tokenizer
from treebook.hourglass import ModelConfig, TreeTransformer
from treebook.train import WEIGHTS
from treebook.growth import complete, containment, decode_growth, encode_growth, generate, grow_sequence, write_growth
from treebook.demos import demo_growth
from treebook.condition import (ConditionalTree, load_conditional, points_to_tree, read_lines, save_conditional, sketch_to_tree,
                                image_to_tree)

torch.set_num_threads(1)


@pytest.fixture(scope="module")
def toy():
    "An untrained tiny model and a tokenizer fitted to small grown elms: enough to test prompt handling."
    trees = [grow("elm", seed=s, max_branches=40)[-1] for s in range(6)]
    torch.manual_seed(0)
    return TreeTransformer(ModelConfig(arch="full", dim=32, depth=5, heads=2, max_len=520)), Tokenizer.fit(trees)


@pytest.mark.parametrize("order", ["dfs", "bfs"])
@pytest.mark.parametrize("k", [1, 7, 20])
def test_completion_keeps_prompt_exactly(toy, order, k):
    full = grow("elm", seed=11, max_branches=40)[-1]
    part = full.prefix(k, order)
    net, tok = toy
    out = complete(part, n=4, seed=3, model=toy, order=order)
    o = tok.order(part, order, normalize=False)
    ref = part.take(o)
    for t in out:
        assert np.array_equal(t.start[:k], ref.start) and np.array_equal(t.end[:k], ref.end)
        assert np.array_equal(t.parent[:k], ref.parent) and t.prompt[:k].all() and not t.prompt[k:].any()
        assert t.n > k
        kids = np.flatnonzero((t.parent >= 0) & (np.arange(t.n) >= k))
        assert np.allclose(t.start[kids, :3], t.end[t.parent[kids], :3], atol=1e-5)  # new branches attach exactly
    assert len({t.n for t in out}) > 1 or any(not np.array_equal(out[0].end, t.end) for t in out[1:])
    again = complete(part, n=4, seed=3, model=toy, order=order)
    assert all(a == b for a, b in zip(out, again))


def test_completion_other_frame_and_path(toy, tmp_path):
    part = grow("elm", seed=5, max_branches=40)[-1].prefix(9).scale(12.0).translate((3, -4, 100))
    path = part.save(tmp_path / "partial.npz")
    out = complete(path, n=2, seed=0, model=toy)
    o = toy[1].order(part, "dfs")
    for t in out:
        assert np.array_equal(t.end[:9], part.take(o).end)
        assert t.start[:, 2].min() >= 99 and t.height < 20   # completions live in the partial tree's units


def test_completion_errors(toy, tmp_path):
    with pytest.raises(TreebookError, match="empty"): complete(Tree.empty(), model=toy)
    two = Tree(np.array([[0, 0, 0, .01], [1, 0, 0, .01]]), np.array([[0, 0, 1, .01], [1, 0, 1, .01]]), [-1, -1])
    with pytest.raises(TreebookError, match="2 roots"): complete(two, model=toy)
    with pytest.raises(TreebookError, match="no such file"): complete(tmp_path / "none.npz", model=toy)
    with pytest.raises(TreebookError, match="no shipped model"): complete(two.take([0]), model="no-such-model")
    big = grow("elm", seed=1)[-1]
    with pytest.raises(TreebookError, match="no room"): complete(big, model=toy)


@pytest.mark.skipif(not (WEIGHTS / "elm.pt").is_file(), reason="the shipped elm model is not installed yet")
def test_completion_with_shipped_elm():
    part = grow("elm", seed=123)[-1].prefix(15)
    out = complete(part, n=2, seed=0, model="elm")
    for t in out: assert t.n > 15 and t.prompt.sum() == 15


def test_growth_layouts_round_trip(toy):
    _, tok = toy
    h = grow("elm", seed=2, max_branches=40)
    for mode in ("incremental", "full"):
        seq = encode_growth(tok, h, mode=mode)
        assert (seq == STAGE).sum() == 72
        back = decode_growth(tok, seq, mode=mode)
        assert [t.n for t in back] == [t.n for t in h] and containment(back, tok) == 1.0


def test_sampled_growth_has_all_stages(toy, tmp_path):
    net, tok = toy
    stages = grow_sequence(toy, seed=4)
    assert len(stages) == 10 and all(t.n for t in stages) and containment(stages, tok) == 1.0
    paths = write_growth(stages, tmp_path / "g")
    names = {p.name for p in paths}
    assert {"stage_00.npz", "stage_09.npz", "stage_09.obj", "growth_filmstrip.png", "growth.gif"} <= names
    assert Tree.load(tmp_path / "g" / "stage_09.npz").n == stages[-1].n


def test_missing_weights_say_what_to_do():
    if not (WEIGHTS / "elm-grow.pt").is_file():
        with pytest.raises(TreebookError, match="no shipped model called 'elm-grow'"): grow_sequence("elm-grow")
    with pytest.raises(TreebookError, match="no shipped conditional model"): load_conditional("elm-nothing")


def test_demo_growth_without_weights(tmp_path, monkeypatch):
    "A fresh checkout without the growth and image weights still gets a (procedural) filmstrip."
    import treebook.train
    monkeypatch.setattr(treebook.train, "WEIGHTS", tmp_path / "no-weights")
    paths = demo_growth(tmp_path, seed=0)
    assert (tmp_path / "growth_procedural" / "growth_filmstrip.png") in paths and all(Path(p).exists() for p in paths)


@pytest.mark.skipif(not (WEIGHTS / "elm-grow.pt").is_file(), reason="elm-grow is not shipped")
def test_shipped_growth_model():
    "The shipped elm-grow writes ten stages, each contained in the next (a few seconds of sampling)."
    from treebook.train import load_pretrained
    net, tok = load_pretrained("elm-grow")
    stages = grow_sequence((net, tok), seed=0)
    assert len(stages) == 10 and stages[-1].n > stages[0].n and containment(stages, tok) == 1.0


def test_sketch_files(toy, tmp_path):
    net, tok = toy
    model = (ConditionalTree("sketch", net, heads=2).eval(), tok)
    (tmp_path / "empty.json").write_text("")
    with pytest.raises(TreebookError, match="no line segments"): sketch_to_tree(tmp_path / "empty.json", model=model)
    (tmp_path / "bad.json").write_text('{"lines": [[1, 2, 3]]}')
    with pytest.raises(TreebookError, match="list of segments"): sketch_to_tree(tmp_path / "bad.json", model=model)
    (tmp_path / "flat.json").write_text(json.dumps([[0, 5, 10, 5]]))
    with pytest.raises(TreebookError, match="no height"): sketch_to_tree(tmp_path / "flat.json", model=model)
    (tmp_path / "t.svg").write_text('<svg><line x1="50" y1="100" x2="50" y2="60"/><path d="M50 60 L30 30 M50 60 L70 25"/></svg>')
    (tmp_path / "t.json").write_text(json.dumps([[50, 100, 50, 60], [50, 60, 30, 30], [50, 60, 70, 25]]))
    assert np.allclose(read_lines(tmp_path / "t.svg"), read_lines(tmp_path / "t.json"))
    a = sketch_to_tree(tmp_path / "t.svg", n=2, seed=1, model=model)
    b = sketch_to_tree(tmp_path / "t.json", n=2, seed=1, model=model)
    assert len(a) == 2 and all(x == y for x, y in zip(a, b))
    with pytest.raises(TreebookError, match="sketch"): sketch_to_tree(tmp_path / "t.txt", model=model)


def test_points_and_image_to_tree(toy, tmp_path):
    from treebook.metrics import sample_surface
    from treebook.scan import silhouette
    net, tok = toy
    pm = (ConditionalTree("points", net, heads=2).eval(), tok)
    t = grow("elm", seed=9, max_branches=40)[-1]
    cloud = sample_surface(t, 3000) * 8 + np.array([10, 20, 30])
    np.savetxt(tmp_path / "scan.xyz", cloud)
    out = points_to_tree(tmp_path / "scan.xyz", n=2, seed=0, model=pm)
    assert len(out) == 2 and all(29 < g.start[0, 2] < 31.5 for g in out)
    with pytest.raises(TreebookError, match="empty"): points_to_tree(np.zeros((0, 3)), model=pm)
    im = (ConditionalTree("image", net, heads=2).eval(), tok)
    assert image_to_tree(silhouette(t), n=1, model=im)[0].n >= 1
    with pytest.raises(TreebookError, match="no such image"): image_to_tree(tmp_path / "none.png", model=im)
    save_conditional(im[0], tok, tmp_path / "im.pt")
    assert load_conditional(tmp_path / "im.pt")[0].kind == "image"


def test_widgets_headless(toy):
    from treebook.widgets import GrowthExplorer, SampleExplorer
    x = SampleExplorer({"toy": toy})
    t0, png0 = x.tree, x.image.value
    x.temperature.value = 1.3
    assert x.tree != t0 and x.image.value != png0
    x.temperature.value = 0.9
    assert x.tree == t0
    x.top_p.value = 0.2
    assert x.tree != t0
    g = GrowthExplorer({"elm (procedural)": ("species", "elm"), "toy": toy})
    n9 = g.tree.n
    g.stage.value = 3
    assert g.tree.n < n9
    s3 = g.tree
    g.source.value = "toy"
    assert g.tree != s3 and len(g.history) == 10


@pytest.mark.parametrize("name, before", [("elm-image", 0.002), ("elm-points", 0.0001)])
def test_shipped_model_reads_its_input(name, before):
    "The shipped elm-image (2D glimpse) and elm-points (3D glimpse) predict a tree's tokens better from its own input than from another tree's."
    from treebook.condition import cond_batch, input_reliance
    model, tok = load_conditional(name)
    assert model.glimpse is not None and model.glimpse.volume == (model.kind == "points")
    trees = [grow("elm", seed=900 + s)[-1] for s in range(4)]
    r = input_reliance(model, cond_batch(model.kind, trees, tok, 0, 4, 0, "dfs", False))
    assert r["gap"] > 0.02, r   # nats per token; the models before the glimpse showed at most `before`
