"""`treebook reconstruct` on worker processes and on a dask cluster: the same trees, meshes and summary.csv as one scan
after another; a bad file is one line in every mode, a worker that dies one failed file."""
import os
import shutil
import signal
import socket
import sys

import numpy as np
import pytest
from test_reconstruct_batch import run, scans  # noqa: F401 (the fixture: two scans of trees and a broken file)

from treebook.cli import dask_client, run_batch
from treebook.pointio import read_fields, read_points, write_points
from treebook.tree import Tree, TreebookError

MADE = ["summary.csv"] + [f"tree{i}{s}" for i in range(2) for s in (".npz", ".obj", "_labels.ply")]


@pytest.fixture(scope="module")
def plot(scans, tmp_path_factory):
    "The scans of two trees, a broken file, refused when read (in the main process), and a plane its worker refuses."
    d = tmp_path_factory.mktemp("plot")
    for f in scans.glob("*.xyz"): shutil.copy(f, d)
    flat = np.random.default_rng(0).random((300, 2))
    np.savetxt(d / "flat.xyz", np.c_[flat, np.zeros(300)], fmt="%.5f")
    return d


def batch(treebook_cmd, plot, out, *how, made=2):
    r = run(treebook_cmd, "reconstruct", plot, "--out", out, "--method", "classic", "--mesh", "obj", "--labels", "ply",
            *how)
    assert r.returncode == 2, r.stderr
    errors = [l for l in r.stderr.splitlines() if l.startswith("error:")]
    assert sorted(l.split(":")[1].strip() for l in errors) == ["broken.xyz", "flat.xyz"], r.stderr
    assert f"{made} reconstructed, {2 - made} already there, 2 failed, of 4 scans" in r.stdout, r.stdout
    return r


@pytest.fixture(scope="module")
def one_by_one(treebook_cmd, plot, tmp_path_factory):
    out = tmp_path_factory.mktemp("one") / "trees"
    batch(treebook_cmd, plot, out, "--workers", "1")
    return out


def same(a, b):
    assert sorted(p.name for p in a.iterdir()) == sorted(p.name for p in b.iterdir()) == MADE
    for n in MADE:
        if n.endswith(".npz"):
            assert Tree.load(a / n) == Tree.load(b / n), n
            with np.load(a / n) as x, np.load(b / n) as y:
                assert x.files == y.files and all(np.array_equal(x[k], y[k]) for k in x.files), n
        else: assert (a / n).read_bytes() == (b / n).read_bytes(), n


def test_workers_make_the_same(treebook_cmd, plot, one_by_one, tmp_path):
    batch(treebook_cmd, plot, tmp_path / "trees", "--workers", "2")
    same(one_by_one, tmp_path / "trees")
    (tmp_path / "trees" / "summary.csv").unlink()   # a second run skips what is done, its rows made again
    batch(treebook_cmd, plot, tmp_path / "trees", "--workers", "2", made=0)
    same(one_by_one, tmp_path / "trees")


def test_dask_makes_the_same(treebook_cmd, plot, one_by_one, tmp_path):
    distributed = pytest.importorskip("distributed")
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as c:
        batch(treebook_cmd, plot, tmp_path / "trees", "--scheduler", c.scheduler_address)
    same(one_by_one, tmp_path / "trees")


def test_no_scheduler_is_one_line(treebook_cmd, plot, tmp_path):
    with socket.socket() as s:   # a port that no one listens on
        s.bind(("127.0.0.1", 0)); port = s.getsockname()[1]
    r = run(treebook_cmd, "reconstruct", plot, "--out", tmp_path / "t", "--scheduler", f"tcp://127.0.0.1:{port}")
    assert r.returncode == 2 and r.stderr.count("\n") == 1, r.stderr
    assert r.stderr.startswith(f"error: cannot reach the dask scheduler at tcp://127.0.0.1:{port}"), r.stderr
    assert not (tmp_path / "t").exists()


def test_no_distributed_says_what_to_install(monkeypatch):
    monkeypatch.setitem(sys.modules, "distributed", None)   # as if not installed
    with pytest.raises(TreebookError, match="pip install distributed"): dask_client("tcp://127.0.0.1:8786")


def test_labels_follow_a_las_scan(treebook_cmd, scans, tmp_path):
    write_points(tmp_path / "s.las", read_points(scans / "tree0.xyz"), scale=0.0001)
    r = run(treebook_cmd, "reconstruct", tmp_path / "s.las", "--method", "classic", "--labels", "las",
            "--out", tmp_path / "t.npz")
    assert r.returncode == 0, r.stderr
    got, n = read_fields(tmp_path / "t_labels.las"), Tree.load(tmp_path / "t.npz").n
    assert np.array_equal(read_points(tmp_path / "t_labels.las"), read_points(tmp_path / "s.las"))   # same points, scale
    assert sorted(got) == ["segment", "tree"] and np.array_equal(got["tree"] == 1, got["segment"] >= 0)
    assert got["segment"].max() < n and (got["segment"] >= 0).mean() > 0.9


def crash_on_b(name, data, options):
    "A job whose worker process dies on b.txt."
    if name == "b.txt": os.kill(os.getpid(), signal.SIGSEGV)
    return name.upper()


def test_a_dying_worker_fails_its_file_alone(tmp_path, capsys):
    got = {}
    code = run_batch([tmp_path / f"{c}.txt" for c in "abcde"], crash_on_b, {}, lambda f, r: got.update({f.name: r}),
                     workers=2)
    assert code == 2 and got == {f"{c}.txt": f"{c.upper()}.TXT" for c in "acde"}
    err = capsys.readouterr().err
    assert err.count("error:") == 1 and "error: b.txt: its worker process died" in err, err
