"""scripts/partnet.py pool-pack (treebook.partnet_runs): a further train pool made with its own tree seeds, packed, and unpacked together with another
into one pool that partnet.py train loads, each scan's points and labels as they were scanned (to 16-bit steps of its box)."""
import subprocess, sys
from pathlib import Path
import numpy as np
from scipy.spatial import cKDTree

ROOT = Path(__file__).resolve().parent.parent
from treebook.partnet_runs import load_or_make_pool, make_packed_pool, make_pool, unpack_pools
from treebook.botany import SPECIES


def test_make_and_unpack_several(tmp_path):
    make_packed_pool(2, 1, tmp_path / "a" / "s2.npz", n_points=256)     # the parent folder is made
    make_packed_pool(3, 1, tmp_path / "s3.npz", n_points=256)
    unpack_pools(f"{tmp_path / 'a' / 's2.npz'},{tmp_path / 's3.npz'}", tmp_path / "work")
    got = load_or_make_pool(tmp_path / "work" / "train_pool.npz")
    assert len(got) == 2 * len(SPECIES) and all(len(g["points"]) == 256 for g in got)
    assert load_or_make_pool(tmp_path / "work" / "test_pool.npz") == []   # none packed: an empty one
    want = make_pool(1, seed=2, n_points=256, desc="s2") + make_pool(1, seed=3, n_points=256, desc="s3")
    for g, w in zip(got, want):
        assert g["species"] == w["species"]
        d, match = cKDTree(w["points"]).query(g["points"])                 # another order, the same points: each one's nearest
        assert len(set(match)) == len(match) and d.max() <= np.ptp(w["points"], 0).max() / 65535 + 1e-5
        np.testing.assert_array_equal(g["part"], w["part"][match])
        np.testing.assert_array_equal(g["junction"], w["junction"][match])
    assert not np.allclose(got[0]["points"].mean(0), got[len(SPECIES)]["points"].mean(0))   # two seeds, two different trees


def test_usage():
    r = subprocess.run([sys.executable, str(ROOT / "scripts" / "partnet.py"), "pool-pack", "make", "2", "1"], capture_output=True, text=True)
    assert r.returncode != 0 and "Usage" in r.stderr
