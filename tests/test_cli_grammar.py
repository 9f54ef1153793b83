"""`treebook grammar | enhance | propagate` end to end on every shared real scan (subprocesses)."""
import json
import subprocess

import pytest

from treebook.tree import Tree

SCANS = ["tree1.xyz", "tree7.xyz", "tree13.xyz", "pytlidar_tree_1.las"]


def run(*args):
    return subprocess.run([str(a) for a in args], capture_output=True, text=True, timeout=300)


@pytest.mark.parametrize("name", SCANS)
def test_grammar_propagate_enhance_on_real_scans(treebook_cmd, shared_scans, tmp_path, name):
    scan = shared_scans / name
    if not scan.exists(): pytest.skip(f"{scan} not available")
    r = run(treebook_cmd, "grammar", scan, "--grid", "128", "--out", tmp_path / "g.json")
    assert r.returncode == 0, r.stderr
    assert "lossless" in r.stdout and "wrote" in r.stdout
    g = json.loads((tmp_path / "g.json").read_text())
    assert g
    r = run(treebook_cmd, "propagate", tmp_path / "g.json", "--n", "3", "--seed", "1", "--out", tmp_path / "prop")
    assert r.returncode == 0, r.stderr
    trees = [Tree.load(tmp_path / "prop" / f"propagated_{k:03d}.npz") for k in range(3)]
    assert len({t.end.tobytes() for t in trees}) == 3  # three different trees
    r = run(treebook_cmd, "enhance", scan, "--levels", "1", "--out", tmp_path / "enh")
    assert r.returncode == 0, r.stderr
    assert Tree.load(tmp_path / "enh" / "enhanced.npz").n > 0


def test_grammar_bad_inputs(treebook_cmd, tmp_path):
    (tmp_path / "empty.xyz").write_text("")
    (tmp_path / "few.xyz").write_text("0 0 0\n1 1 1\n")
    for args, msg in [(["grammar", tmp_path / "empty.xyz"], ""), (["grammar", tmp_path / "few.xyz"], ""),
                      (["grammar", tmp_path / "nope.las"], "no such file")]:
        r = run(treebook_cmd, *args, "--out", tmp_path / "g.json")
        assert r.returncode == 2 and r.stderr.startswith("error: ") and r.stderr.count("\n") == 1 and msg in r.stderr, r.stderr
        assert not (tmp_path / "g.json").exists()


@pytest.mark.parametrize("name", ["elm", "spruce"])
def test_grammar_commands_on_procedural_scans(treebook_cmd, tmp_path, name):
    "The same three commands on a virtual scan of a grown tree (scaled to 8 m, saved as .npy)."
    import numpy as np
    from treebook.botany import grow_tree
    from treebook.scan import scan
    s = scan(grow_tree(name, seed=3), n_points=16384, seed=3)
    np.save(tmp_path / "scan.npy", s.points * 8.0)
    r = run(treebook_cmd, "grammar", tmp_path / "scan.npy", "--grid", "128", "--out", tmp_path / "g.json")
    assert r.returncode == 0, r.stderr
    r = run(treebook_cmd, "propagate", tmp_path / "g.json", "--n", "2", "--out", tmp_path / "prop")
    assert r.returncode == 0, r.stderr
    a, b = (Tree.load(tmp_path / "prop" / f"propagated_{k:03d}.npz") for k in range(2))
    assert not np.array_equal(a.end, b.end)
    r = run(treebook_cmd, "enhance", tmp_path / "scan.npy", "--out", tmp_path / "enh")
    assert r.returncode == 0, r.stderr
