"""`treebook reconstruct` on several scans or a folder: one process, one tree each, bad files reported and skipped."""
import subprocess
from pathlib import Path

import numpy as np
import pytest

from treebook.scan import scan
from treebook.tree import Tree, example_tree


def run(cmd, *args):
    return subprocess.run([cmd, *map(str, args)], capture_output=True, text=True, timeout=300)


@pytest.fixture(scope="module")
def scans(tmp_path_factory):
    d = tmp_path_factory.mktemp("scans")
    for i in range(2):
        p = scan(example_tree(levels=3, seed=i), n_points=2500, seed=i, noise=0.001, outliers=0.0).points
        np.savetxt(d / f"tree{i}.xyz", p, fmt="%.5f")
    (d / "broken.xyz").write_text("1 2 3\n")
    (d / "notes.md").write_text("not a scan")
    return d


def test_folder_with_a_bad_file(treebook_cmd, scans, tmp_path):
    out = tmp_path / "trees"
    r = run(treebook_cmd, "reconstruct", scans, "--out", out, "--mesh", "obj", "--method", "classic")
    assert r.returncode == 2                                          # one scan failed ...
    assert [l for l in r.stderr.splitlines() if l.startswith("error:")] == [
        l for l in r.stderr.splitlines() if "broken.xyz" in l]        # ... on one line of its own
    assert sorted(p.name for p in out.iterdir()) == ["summary.csv", "tree0.npz", "tree0.obj", "tree1.npz", "tree1.obj"]
    assert "2 reconstructed, 0 already there, 1 failed, of 3 scans" in r.stdout
    for i in range(2): assert Tree.load(out / f"tree{i}.npz").n > 10
    again = run(treebook_cmd, "reconstruct", scans, "--out", out, "--mesh", "obj", "--method", "classic")
    assert "0 reconstructed, 2 already there, 1 failed" in again.stdout   # a second run skips what is done


def test_several_files_match_one_by_one(treebook_cmd, scans, tmp_path):
    r = run(treebook_cmd, "reconstruct", scans / "tree0.xyz", scans / "tree1.xyz", "--out", tmp_path / "b")
    assert r.returncode == 0, r.stderr
    one = run(treebook_cmd, "reconstruct", scans / "tree1.xyz", "--out", tmp_path / "one.npz")
    assert one.returncode == 0, one.stderr
    assert Tree.load(tmp_path / "b" / "tree1.npz") == Tree.load(tmp_path / "one.npz")


@pytest.mark.parametrize("args, says", [
    (["{s}", "--out", "{o}/x.npz"], "names a file"),
    (["{s}", "--out", "{o}/t", "--mesh", "stl"], "names a format"),
    (["{s}", "--out", "{o}/t", "--skeleton", "obj"], "names a format"),
    (["{e}", "--out", "{o}/t"], "no scans in folder"),
    (["{s}/tree0.xyz", "{s}/tree0.xyz", "--out", "{o}/t"], "same tree"),
])
def test_bad_batches_say_one_line(treebook_cmd, scans, tmp_path, args, says):
    (tmp_path / "empty").mkdir()
    r = run(treebook_cmd, "reconstruct", *[a.format(s=scans, o=tmp_path, e=tmp_path / "empty") for a in args])
    assert r.returncode == 2 and says in r.stderr and len(r.stderr.strip().splitlines()) == 1, r.stderr
    assert not (tmp_path / "t").exists() and not (tmp_path / "x.npz").exists()   # nothing written
