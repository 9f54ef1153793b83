"Tests of the hourglass transformer (treebook.hourglass) and its sampler (treebook.sampling); tiny configs only."
from types import SimpleNamespace

import numpy as np
import pytest
import torch
from hypothesis import given, settings, strategies as st

from treebook.hourglass import (ARCHS, DecodeState, ModelConfig, TreeTransformer, check_cache, check_causal,
                                shorten, lengthen)
from treebook.sampling import CONTRACT, TreeGrammar, pick, sample, token_connectivity
from treebook.tree import TreebookError

TINY = dict(dim=32, depth=8, heads=2, max_len=128)
FAKE = SimpleNamespace(**vars(CONTRACT), root_tokens=(128, 128, 0), min_radius_token=2)


@pytest.fixture(scope="module", autouse=True)
def one_thread():
    "Tiny models run faster on one thread, and much faster when other jobs share the cores."
    n = torch.get_num_threads(); torch.set_num_threads(1)
    yield
    torch.set_num_threads(n)


@pytest.fixture(scope="module")
def models(one_thread):
    out = {}
    for i, arch in enumerate(ARCHS):
        torch.manual_seed(i)
        out[arch] = TreeTransformer(ModelConfig(arch=arch, **TINY)).eval()
    return out


@pytest.mark.parametrize("arch", ARCHS)
@pytest.mark.parametrize("length", [8, 13, 21, 30])
def test_causal(models, arch, length):
    assert check_causal(models[arch], length=length) <= 1e-5


@settings(max_examples=25, deadline=None)
@given(arch=st.sampled_from(ARCHS), length=st.integers(2, 40), data=st.data())
def test_causal_property(models, arch, length, data):
    "Changing tokens after a random t leaves logits at <= t unchanged, for any length (multiples of 8 or not)."
    m = models[arch]
    t = data.draw(st.integers(0, length - 2))
    seed = data.draw(st.integers(0, 2**16))
    g = torch.Generator().manual_seed(seed)
    x = torch.randint(0, 264, (1, length), generator=g)
    x2 = x.clone(); x2[:, t + 1:] = torch.randint(0, 264, (1, length - t - 1), generator=g)
    with torch.no_grad():
        torch.testing.assert_close(m(x)[:, :t + 1], m(x2)[:, :t + 1], atol=1e-5, rtol=0)


def test_pooling_groups():
    pos = torch.arange(16.).view(1, 16, 1)
    assert shorten(pos, 4).flatten().tolist() == [0.0, 2.5, 6.5, 10.5]
    # branch b = mean of points 2b-1, 2b: it has seen tokens up to 8b and serves positions 8b..8b+7
    assert lengthen(shorten(shorten(pos, 4), 2), 8).flatten().tolist() == [0.0] * 8 + [4.5] * 8


@pytest.mark.parametrize("arch", ARCHS)
@pytest.mark.parametrize("prompt", [0, 1, 7, 11, 24])
def test_cache_matches_forward(models, arch, prompt):
    assert check_cache(models[arch], length=37, prompt=prompt) <= 1e-4


@pytest.mark.parametrize("arch", ARCHS)
@pytest.mark.parametrize("prompt", [None, [256] * 8 + [128, 128, 0, 9, 130, 120, 40, 7, 130]])
@pytest.mark.parametrize("structure", [True, False])
def test_cached_greedy_equals_recomputation(models, arch, prompt, structure):
    kw = dict(tok=FAKE, prompt=prompt, max_len=53, min_len=53, temperature=0, structure=structure, return_logits=True)
    a, la = sample(models[arch], 2, **kw)
    b, lb = sample(models[arch], 2, cache=False, **kw)
    assert [s.tolist() for s in a] == [s.tolist() for s in b]
    torch.testing.assert_close(la, lb, atol=1e-4, rtol=1e-4)


def test_sampling_options_are_deterministic(models):
    m = models["full"]
    for kw in (dict(top_k=5), dict(top_p=0.9), dict(temperature=0.7), dict(structure=False)):
        a = sample(m, 3, tok=FAKE, max_len=64, seed=11, **kw)
        b = sample(m, 3, tok=FAKE, max_len=64, seed=11, **kw)
        assert [s.tolist() for s in a] == [s.tolist() for s in b]


@pytest.mark.parametrize("arch", ARCHS)
def test_structure_aware_sampling_is_connected(models, arch):
    out = sample(models[arch], 6, tok=FAKE, max_len=128, min_len=64, seed=3)
    for s in out:
        assert token_connectivity(s, FAKE) == 1.0
        assert len(s) % 8 == 0 and (s[:8] == 256).all() and (s[-8:] == 257).all()
        v = s[8:-8].reshape(-1, 8)
        assert (v < 256).all() and (v[:, [3, 7]] >= FAKE.min_radius_token).all()
        assert len(v) >= 7


def test_structure_with_real_tokenizer(models):
    tokens = pytest.importorskip("treebook.tokens")
    from treebook.tree import example_tree
    tok = tokens.Tokenizer.fit([example_tree(levels=4, seed=s) for s in range(3)])
    out = sample(models["full"], 8, tok=tok, max_len=128, min_len=40, seed=0, temperature=1.5)
    for s in out:
        c = tok.connectivity(s)
        assert c.connected and c.connect == 1.0
        tree = tok.decode(s, strict=True)
        assert tree.n == len(s) // 8 - 2 and (tree.parent < 0).sum() == 1
        assert (tree.start[:, 3] > 0).all() and (tree.end[:, 3] > 0).all()


def test_prompt_completion_keeps_prompt(models):
    pr = [256] * 8 + [128, 128, 0, 9, 130, 120, 40, 7]
    for s in sample(models["hg2"], 3, tok=FAKE, prompt=pr, max_len=96, seed=2):
        assert s[:16].tolist() == pr and token_connectivity(s, FAKE) == 1.0
    off_root = sample(models["hg2"], 1, tok=FAKE, prompt=[256] * 8 + [1, 2, 3], max_len=64, seed=2)[0]
    assert off_root[8:11].tolist() == [1, 2, 3]   # a prompt may start elsewhere: the grammar continues from it
    with pytest.raises(TreebookError, match="no earlier branch's end"):
        sample(models["hg2"], 1, tok=FAKE, prompt=[256] * 8 + [128, 128, 0, 9, 130, 120, 40, 7, 5], max_len=64)


def test_sampler_errors(models):
    m = models["full"]
    with pytest.raises(TreebookError, match="needs the fitted tokenizer"): sample(m, 1)
    with pytest.raises(TreebookError, match="longer than the model's max_len"): sample(m, 1, tok=FAKE, max_len=500)
    with pytest.raises(TreebookError, match="empty"): sample(m, 1, tok=FAKE, prompt=[])
    with pytest.raises(TreebookError, match="lie in"): sample(m, 1, tok=FAKE, prompt=[300])
    with pytest.raises(TreebookError, match="no room"): sample(m, 1, tok=FAKE, prompt=[256] * 64, max_len=64)
    with pytest.raises(TreebookError, match="too short"): sample(m, 1, tok=FAKE, max_len=20)
    with pytest.raises(TreebookError, match="capacity"): m.extend(torch.zeros(1, 200, dtype=torch.long), DecodeState(m, 1, 128))


def test_pick():
    lg = torch.tensor([[0., 3., 1., 2.]])
    assert pick(lg, temperature=0).item() == 1
    allowed = torch.tensor([[True, False, True, False]])
    g = torch.Generator().manual_seed(0)
    assert all(pick(lg, allowed, generator=g).item() in (0, 2) for _ in range(50))


def test_grammar_eos_only_at_boundaries():
    gr = TreeGrammar(FAKE, 1, 64)
    for t in range(8, 16):
        assert not gr.allowed(t)[0, 257]
        gr.observe([[128, 128, 0, 5, 140, 128, 20, 4][t - 8]], t)
    assert gr.allowed(16)[0, 257] and not gr.allowed(16)[0, 128]
    assert gr.allowed(16)[0, 140]


def test_checkpoint_round_trip_and_errors(models, tmp_path):
    m = models["full"]
    p = m.save(tmp_path / "m.pt", steps=3)
    assert not list(tmp_path.glob("*.part"))
    x = torch.randint(0, 256, (2, 19))
    with torch.no_grad(): assert torch.equal(TreeTransformer.load(p)(x), m(x))
    assert TreeTransformer.load(p, ModelConfig(arch="full", **TINY)).config == m.config
    data = p.read_bytes()
    for cut in (0, 10, len(data) // 2, len(data) - 5):
        (tmp_path / "cut.pt").write_bytes(data[:cut])
        with pytest.raises(TreebookError, match="truncated"): TreeTransformer.load(tmp_path / "cut.pt")
    with pytest.raises(TreebookError, match="does not exist"): TreeTransformer.load(tmp_path / "nope.pt")
    with pytest.raises(TreebookError, match="different config"): TreeTransformer.load(p, ModelConfig(arch="hg2", **TINY))
    ck = torch.load(p, weights_only=True)
    ck["config"]["arch"] = "pt"; torch.save(ck, tmp_path / "mis.pt")
    with pytest.raises(TreebookError, match="do not match its config"): TreeTransformer.load(tmp_path / "mis.pt")
    ck["config"]["arch"] = "nope"; torch.save(ck, tmp_path / "arch.pt")
    with pytest.raises(TreebookError, match="unknown arch"): TreeTransformer.load(tmp_path / "arch.pt")
    ck["version"] = 0; torch.save(ck, tmp_path / "v0.pt")
    with pytest.raises(TreebookError, match="checkpoint version 0"): TreeTransformer.load(tmp_path / "v0.pt")
    torch.save([1, 2], tmp_path / "list.pt")
    with pytest.raises(TreebookError, match="not a treebook hourglass checkpoint"): TreeTransformer.load(tmp_path / "list.pt")
    with pytest.raises(TreebookError, match="does not exist"): m.save(tmp_path / "no" / "dir" / "m.pt")


def test_config_errors():
    with pytest.raises(TreebookError, match="unknown arch"): ModelConfig(arch="hg3")
    with pytest.raises(TreebookError, match="multiple of heads"): ModelConfig(dim=30, heads=4)
    with pytest.raises(TreebookError, match="needs depth"): ModelConfig(arch="hg1", depth=2)
    m = TreeTransformer(ModelConfig(arch="pt", dim=16, depth=1, heads=2, max_len=16))
    with pytest.raises(TreebookError, match="longer than"): m(torch.zeros(1, 17, dtype=torch.long))


def test_variants_differ_as_configured():
    counts = {a: TreeTransformer(ModelConfig(arch=a, **TINY)) for a in ARCHS}
    assert len(counts["pt"].mid) == 8 and len(counts["hg1"].mid) == 6 and len(counts["full"].mid) == 4
    assert counts["full"].alpha.requires_grad and not counts["hg2r"].alpha.requires_grad
    assert len(counts["hg2"].alpha) == 0 and len(counts["full"].alpha) == 2


def test_pick_follows_the_distribution():
    logits = torch.tensor([0.5, 1.5, -1.0, 0.0, -40.0])
    draws = pick(logits.repeat(50000, 1), generator=torch.Generator().manual_seed(1))
    freq = torch.bincount(draws, minlength=5).float() / 50000
    torch.testing.assert_close(freq, logits.softmax(-1), atol=0.01, rtol=0)
    top2 = pick(logits.repeat(2000, 1), top_k=2, generator=torch.Generator().manual_seed(2))
    assert set(top2.tolist()) == {0, 1}


@pytest.mark.parametrize("arch", ["hg1", "full"])
def test_one_prompt_per_row(models, arch):
    rows = np.array([[256] * 8 + [128, 128, 0, 9, 130, 120, 40, 7, 130, 120],
                     [256] * 8 + [128, 128, 0, 4, 100, 90, 80, 3, 100, 90]])
    kw = dict(tok=FAKE, prompt=rows, max_len=48, min_len=48, temperature=0, return_logits=True)
    a, la = sample(models[arch], 2, **kw)
    b, lb = sample(models[arch], 2, cache=False, **kw)
    assert [s.tolist() for s in a] == [s.tolist() for s in b]
    torch.testing.assert_close(la, lb, atol=1e-4, rtol=1e-4)
    for s, r in zip(a, rows):
        assert s[:len(r)].tolist() == r.tolist() and token_connectivity(s, FAKE) == 1.0
    assert a[0][18] == 40 and a[1][18] == 80          # each row's third start coordinate follows its own prompt


@pytest.mark.parametrize("arch", ["hg1", "hg2", "full"])
@pytest.mark.parametrize("window", [1, 5, 8, 16])
@pytest.mark.parametrize("ends", [False, True])
def test_window_is_causal_and_cached(arch, window, ends):
    "A window (with or without ends) in the full-resolution layers: the future moves nothing, the cache agrees."
    torch.manual_seed(window)
    m = TreeTransformer(ModelConfig(arch=arch, window=window, ends=ends, **TINY)).eval()
    assert check_causal(m, length=37) <= 1e-5
    for prompt in (0, 3, 20):
        assert check_cache(m, length=41, prompt=prompt) <= 1e-4
    kw = dict(tok=FAKE, max_len=53, min_len=53, temperature=0, return_logits=True)
    (a, la), (b, lb) = sample(m, 2, **kw), sample(m, 2, cache=False, **kw)
    assert [s.tolist() for s in a] == [s.tolist() for s in b]
    torch.testing.assert_close(la, lb, atol=1e-4, rtol=1e-4)


def test_window_sees_only_the_last_tokens():
    "With window w, the full-resolution attention at t ignores tokens before t-w+1: changing them moves nothing there."
    from treebook.hourglass import Attention
    torch.manual_seed(0)
    att = Attention(ModelConfig(dim=16, heads=2, depth=8, window=4), window=4).eval()
    x = torch.randn(1, 30, 16); x2 = x.clone(); x2[:, :10] = torch.randn(1, 10, 16)
    with torch.no_grad(): y, y2 = att(x), att(x2)
    torch.testing.assert_close(y[:, 13:], y2[:, 13:])       # positions 13.. see 10.. only
    assert (y[:, 10:13] - y2[:, 10:13]).abs().max() > 1e-4


def test_ends_see_every_branch_end():
    "With ends, position t sees, before its window, exactly the positions s with s % 8 == 7 (each branch's last token)."
    from treebook.hourglass import Attention
    torch.manual_seed(0)
    att = Attention(ModelConfig(dim=16, heads=2, depth=8, window=4, ends=True), window=4).eval()
    x = torch.randn(1, 40, 16)
    with torch.no_grad():
        for s, moves in ((7, True), (15, True), (6, False), (12, False)):
            x2 = x.clone(); x2[:, s] = torch.randn(16)
            d = (att(x) - att(x2)).abs().amax(-1)[0]
            assert d[:s].max() < 1e-6                                   # causal
            assert (d[s + 4:].max() > 1e-4) == moves, (s, d)             # beyond the window: only the ends count
