"Tokens: round trips (hypothesis and a data set), a fuzz test of the decoder, Connect of real trees in every order."
import numpy as np
import pytest
from hypothesis import HealthCheck, assume, given, settings, strategies as st

from treebook.tree import Tree, TreebookError, example_tree
from treebook.tokens import (BLOCK, COND, EOS, ORDERS, PAD, SOS, STAGE, VOCAB_SIZE, Connectivity, Tokenizer, _AXIS,
                             seq_length)

try:
    from treebook import botany
except ImportError:  # the botany chapter is optional for these tests
    botany = None


@st.composite
def trees(draw, max_branches=40):
    "A random tree: each branch starts at the end of an earlier one (or at the root), with a random direction, length and radii."
    n = draw(st.integers(1, max_branches))
    seed = draw(st.integers(0, 2**32 - 1))
    rng = np.random.default_rng(seed)
    start, end, parent = np.zeros((n, 4)), np.zeros((n, 4)), np.full(n, -1)
    for i in range(n):
        if i: parent[i] = rng.integers(0, i) if rng.random() < 0.95 else -1
        if parent[i] >= 0: start[i, :3] = end[parent[i], :3]
        d = rng.normal(size=3); d[2] = abs(d[2]) + 0.2
        end[i, :3] = start[i, :3] + d / np.linalg.norm(d) * rng.uniform(0.05, 1.0)
        start[i, 3] = rng.uniform(0.001, 0.1); end[i, 3] = start[i, 3] * rng.uniform(0.3, 1.0)
    scale = draw(st.sampled_from([1e-3, 1.0, 37.0]))
    return Tree(start * scale, end * scale, parent)


def unambiguous(tok, t):
    "No two branches end in one cell, none ends in the root cell or in its own start cell: parents are then fully determined."
    q = tok.quantise(t)
    sk, ek = [tuple(r) for r in q[:, :3]], [tuple(r) for r in q[:, 4:7]]
    root = tuple(tok.root_tokens)
    return len(set(ek)) == len(ek) and root not in ek and all(s != e for s, e in zip(sk, ek)) \
        and all(s == root for s, p in zip(sk, t.parent) if p < 0)


def half_bin_ok(tok, decoded, ref):
    "Every value of `decoded` within half a bin (plus float32 rounding) of the same value of `ref` (both canonical)."
    q = tok.quantise(ref, normalize=False)
    w = tok.bin_widths[_AXIS[None, :], q]
    got = np.concatenate([decoded.start, decoded.end], 1).astype(np.float64)
    want = np.concatenate([ref.start, ref.end], 1).astype(np.float64)
    return bool(np.all(np.abs(got - want) <= w / 2 + 1e-6 * (1 + np.abs(want))))


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(trees(), st.sampled_from(["quantile", "uniform"]), st.sampled_from(["dfs", "bfs"]))
def test_roundtrip_parents_first(t, rule, kind):
    tok = Tokenizer.fit([t], rule=rule, radius_rule=None if rule == "quantile" else "log", margin=0.0)
    s = tok.encode(t, kind)
    assert s.dtype == np.int64 and len(s) == seq_length(t.n)
    d = tok.decode(s)  # never raises; strict may, on an ambiguous or multi-root tree
    assert len(d) == t.n
    ref = t.normalize()[0].take(tok.order(t, kind))
    assert half_bin_ok(tok, d, ref)
    if unambiguous(tok, t):
        d2 = tok.decode(s, strict=True)
        assert d2 == d
        assert d.parent.tolist() == ref.parent.tolist()
        assert tok.encode(d, kind, normalize=False).tolist() == s.tolist()


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(trees(), st.sampled_from(["zyx", "hilbert"]))
def test_roundtrip_spatial_orders(t, kind):
    "zyx and Hilbert may list children first: the same branches and parents come back, sorted parents-first."
    tok = Tokenizer.fit([t], margin=0.0)
    assume(unambiguous(tok, t))
    s = tok.encode(t, kind)
    d = tok.decode(s, strict=True)
    assert len(d) == t.n and np.all(d.parent < np.arange(d.n))
    q = tok.quantise(t)
    qd = tok.quantise(d, normalize=False)
    where = {tuple(r): i for i, r in enumerate(q.tolist())}
    m = np.array([where[tuple(r)] for r in qd.tolist()])  # decoded branch -> original branch
    assert sorted(m.tolist()) == list(range(t.n))
    assert [m[p] if p >= 0 else -1 for p in d.parent] == t.parent[m].tolist()
    assert half_bin_ok(tok, d, t.normalize()[0].take(m))
    assert tok.encode(d, kind, normalize=False).tolist() == s.tolist()
    assert tok.connectivity(s) == Connectivity(1.0, True, t.n)


@settings(max_examples=40, deadline=None)
@given(t=trees(max_branches=15))
def test_save_load_roundtrip(t, tmp_path_factory):
    tok = Tokenizer.fit([t], rule="uniform", radius_rule="log")
    p = tok.save(tmp_path_factory.mktemp("tok") / "tok.json")
    tok2 = Tokenizer.load(p)
    assert np.array_equal(tok2.edges, tok.edges) and tok2.radius_rule == "log"
    assert tok2.encode(t).tolist() == tok.encode(t).tolist()


def real_trees():
    "Grown trees of every species when the botany chapter is there, else procedural example trees."
    if botany is not None:
        return [botany.grow_tree(sp, seed=s, max_branches=200) for sp in botany.SPECIES for s in range(4)]
    return [example_tree(levels, seed=s) for levels in (4, 5, 6) for s in range(8)]


@pytest.fixture(scope="module")
def dataset():
    ts = real_trees()
    return ts, Tokenizer.fit(ts)


@pytest.mark.parametrize("kind", ORDERS)
def test_connect_of_real_trees_is_one(dataset, kind):
    ts, tok = dataset
    for t in ts:
        s = tok.encode(t, kind)
        c = tok.connectivity(s)
        assert c == Connectivity(1.0, True, t.n), (kind, c)
        assert tok.connectivity(tok.decode(s), normalize=False) == c


@pytest.mark.parametrize("kind", ORDERS)
def test_dataset_roundtrip(dataset, kind):
    ts, tok = dataset
    B = tok.encode_batch(ts, kind, length=seq_length(max(t.n for t in ts)))
    for t, d, s in zip(ts, tok.decode_batch(B, strict=True), B):
        assert len(d) == t.n
        assert tok.encode(d, kind, normalize=False, length=B.shape[1]).tolist() == s.tolist()
        if kind in ("dfs", "bfs"):
            ref = t.normalize()[0].take(tok.order(t, kind))
            assert d.parent.tolist() == ref.parent.tolist()
            assert half_bin_ok(tok, d, ref)


def mutate(s, rng):
    "A real sequence, damaged in one or several of the ways a sampler can damage it."
    s = s.copy()
    for _ in range(rng.integers(1, 4)):
        k = rng.integers(0, 9)
        n = len(s)
        if k == 0 and n: s[rng.integers(0, n)] = rng.integers(0, VOCAB_SIZE)                     # substitute
        elif k == 1: s = np.insert(s, rng.integers(0, n + 1), rng.integers(0, VOCAB_SIZE))          # insert
        elif k == 2 and n: s = np.delete(s, rng.integers(0, n))                                    # delete
        elif k == 3: s = s[:rng.integers(0, n + 1)]                                                # truncate
        elif k == 4 and n: s[rng.integers(0, n)] = rng.choice([SOS, EOS, PAD, STAGE, COND])         # a special inside
        elif k == 5 and n > 24:                                                                    # swap two blocks
            i, j = rng.integers(1, n // BLOCK - 1, 2) * BLOCK
            s[i:i + BLOCK], s[j:j + BLOCK] = s[j:j + BLOCK].copy(), s[i:i + BLOCK].copy()
        elif k == 6 and n: s[rng.integers(0, n):] = PAD                                            # padded early
        elif k == 7 and n: s = np.concatenate([s[: rng.integers(0, n)], [STAGE] * BLOCK, s[rng.integers(0, n):]])
        elif k == 8 and n: s[rng.integers(0, n, rng.integers(1, 20))] = rng.integers(0, 256)       # scatter values
    return s


def random_sequence(rng):
    kind = rng.integers(0, 4)
    n = int(rng.integers(0, 400))
    if kind == 0: return rng.integers(0, VOCAB_SIZE, n)                                            # any token
    if kind == 1: return rng.integers(-10, 2 * VOCAB_SIZE, n)                                       # out of vocabulary too
    if kind == 2:                                                                                  # well framed, random values
        return np.concatenate([[SOS] * BLOCK, rng.integers(0, 256, BLOCK * (n // BLOCK)), [EOS] * BLOCK, [PAD] * rng.integers(0, 9)])
    return rng.choice([SOS, EOS, PAD, STAGE, COND, 0, 1, 255], n)                                  # mostly specials


def test_fuzz_decoder(dataset):
    "10,000 random and 10,000 mutated sequences: strict raises only TreebookError, non-strict raises nothing."
    ts, tok = dataset
    rng = np.random.default_rng(2024)
    real = [tok.encode(t, kind) for t in ts[:6] for kind in ORDERS]
    seqs = [random_sequence(rng) for _ in range(10_000)] + [mutate(real[rng.integers(len(real))], rng) for _ in range(10_000)]
    seqs += [np.array([], np.int64), np.array([1.5, np.nan, np.inf, -0.0]), np.array([2**63 - 1, -2**63], np.int64),
             np.array([300, 2**40], np.uint64), np.array([True, False])]
    strict_ok = 0
    for s in seqs:
        t = tok.decode(s)
        assert isinstance(t, Tree) and np.all(t.parent < np.arange(t.n))
        assert isinstance(tok.decode(s, unattached="drop"), Tree)
        c = tok.connectivity(s)
        assert 0.0 <= c.connect <= 1.0
        try:
            tok.decode(s, strict=True); strict_ok += 1
        except TreebookError:
            pass
    assert strict_ok > 100  # the well-framed random sequences include valid ones (and the mutated ones some)


def test_decode_usage_errors(dataset):
    ts, tok = dataset
    with pytest.raises(TreebookError, match="decode_batch"): tok.decode(np.zeros((2, 16), int))
    with pytest.raises(TreebookError, match="integers"): tok.decode(["x", "y"])
    with pytest.raises(TreebookError, match="unattached"): tok.decode([SOS] * 8, unattached="keep")
    with pytest.raises(TreebookError, match="2-D"): tok.decode_batch(np.zeros(16, int))


def test_torch_tensors(dataset):
    torch = pytest.importorskip("torch")
    ts, tok = dataset
    s = tok.encode(ts[0])
    assert tok.decode(torch.as_tensor(s)) == tok.decode(s)
    assert len(tok.decode_batch(torch.as_tensor(tok.encode_batch(ts[:3])))) == 3
