"""Training: exact resume (planned stop and a real kill), two-process DDP, bad input, sampling from a checkpoint."""
import os, signal, subprocess, sys, time
from pathlib import Path
import pytest, torch
from treebook.tree import TreebookError
from treebook.datasets import generate_dataset
from treebook.train import train, sample_trees, load_pretrained

TINY = dict(dim=32, depth=5, heads=2, batch_size=4, steps=8, warmup=2, ckpt_every=2, val_trees=4, progress=False, threads=1)
ROOT = Path(__file__).resolve().parent.parent


@pytest.fixture(scope="module")
def data(tmp_path_factory):
    d = tmp_path_factory.mktemp("train") / "elm"
    generate_dataset("elm", 24, d, max_branches=12, workers=1, seed=0, shard_size=12, test_fraction=0.25)
    return d


def same(a, b):
    return all(torch.equal(x, y) for x, y in zip(a.values(), b.values())) and a.keys() == b.keys()


def weights(path):
    return torch.load(path, weights_only=True)["model"]


def test_resume_is_exact(data, tmp_path):
    full = train(data, tmp_path / "full", **TINY)
    assert full["step"] == 8 and (tmp_path / "full" / "log.csv").exists() and (tmp_path / "full" / "loss.png").exists()
    part = train(data, tmp_path / "part", stop_after=3, **TINY)
    assert part["step"] == 3
    again = train(data, tmp_path / "part", resume=True, **TINY)
    assert again["step"] == 8
    assert same(full["model"].state_dict(), again["model"].state_dict())
    assert same(weights(tmp_path / "full" / "last.pt"), weights(tmp_path / "part" / "last.pt"))


def test_resume_after_kill(data, tmp_path):
    "SIGKILL a training process once it has written a checkpoint, resume it, and compare with an uninterrupted run."
    ref = train(data, tmp_path / "ref", **{**TINY, "steps": 12, "ckpt_every": 1})
    args = [sys.executable, "-m", "treebook.train", "--data", str(data), "--out", str(tmp_path / "k"), "--dim", "32", "--depth", "5",
            "--heads", "2", "--batch-size", "4", "--steps", "12", "--warmup", "2", "--ckpt-every", "1", "--val-trees", "4",
            "--threads", "1", "--quiet"]
    proc = subprocess.Popen(args, cwd=ROOT, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    t0 = time.time()
    while not (tmp_path / "k" / "last.pt").exists() and time.time() - t0 < 120 and proc.poll() is None: time.sleep(0.05)
    proc.send_signal(signal.SIGKILL); proc.wait()
    killed_at = torch.load(tmp_path / "k" / "last.pt", weights_only=True)["step"]
    out = subprocess.run(args + ["--resume"], cwd=ROOT, capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    assert killed_at <= 12
    assert same(weights(tmp_path / "ref" / "last.pt"), weights(tmp_path / "k" / "last.pt"))


def test_ddp_two_processes(data, tmp_path):
    env = {**os.environ, "OMP_NUM_THREADS": "1"}
    out = subprocess.run([sys.executable, "-m", "torch.distributed.run", "--nproc_per_node", "2", "--master_port", "29517",
                          "-m", "treebook.train", "--data", str(data), "--out", str(tmp_path / "ddp"), "--dim", "32", "--depth", "5",
                          "--heads", "2", "--batch-size", "2", "--steps", "4", "--warmup", "1", "--val-trees", "4", "--threads", "1",
                          "--quiet", "--rank-weights"], cwd=ROOT, env=env, capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr[-3000:]
    r0, r1 = (torch.load(tmp_path / "ddp" / f"rank{r}.pt", weights_only=True) for r in (0, 1))
    assert same(r0, r1)
    assert torch.load(tmp_path / "ddp" / "last.pt", weights_only=True)["args"]["world"] == 2
    assert same(r0, weights(tmp_path / "ddp" / "last.pt"))


def test_bad_input(data, tmp_path):
    with pytest.raises(TreebookError, match="does not exist"): train(tmp_path / "nowhere", tmp_path / "o", **TINY)
    (tmp_path / "empty").mkdir()
    with pytest.raises(TreebookError, match="no dataset"): train(tmp_path / "empty", tmp_path / "o", **TINY)
    with pytest.raises(TreebookError, match="unknown order"): train(data, tmp_path / "o", order="spiral", **TINY)
    with pytest.raises(TreebookError, match="unknown arch"): train(data, tmp_path / "o", arch="big", **TINY)
    with pytest.raises(TreebookError, match="nothing to resume"): train(data, tmp_path / "fresh", resume=True, **TINY)
    train(data, tmp_path / "run", stop_after=2, **TINY)
    with pytest.raises(TreebookError, match="already holds a run"): train(data, tmp_path / "run", **TINY)
    with pytest.raises(TreebookError, match="other settings"): train(data, tmp_path / "run", resume=True, **{**TINY, "dim": 64, "heads": 2})
    last = tmp_path / "run" / "last.pt"
    last.write_bytes(last.read_bytes()[:1000])
    with pytest.raises(TreebookError, match="truncated"): train(data, tmp_path / "run", resume=True, **TINY)
    with pytest.raises(TreebookError, match="batch"): train(data, tmp_path / "o2", **{**TINY, "batch_size": 1000})


def test_cli_errors(data, tmp_path):
    out = subprocess.run([sys.executable, "-m", "treebook.train", "--data", str(tmp_path / "nope"), "--out", str(tmp_path / "o")],
                         cwd=ROOT, capture_output=True, text=True)
    assert out.returncode == 2 and "does not exist" in out.stderr
    out = subprocess.run([sys.executable, "-m", "treebook.train", "--data", str(data), "--out", str(tmp_path / "o"), "--order", "spiral"],
                         cwd=ROOT, capture_output=True, text=True)
    assert out.returncode == 2 and "invalid choice" in out.stderr


def test_sample_from_checkpoint(data, tmp_path):
    train(data, tmp_path / "s", **TINY)
    a = sample_trees(3, model=str(tmp_path / "s" / "best.pt"), seed=1)
    b = sample_trees(3, model=str(tmp_path / "s" / "best.pt"), seed=1)
    assert len(a) == 3 and all(t.n >= 1 for t in a)
    assert all((x.end == y.end).all() for x, y in zip(a, b))
    with pytest.raises(TreebookError, match="no shipped model"): sample_trees(2, model="oak")
    with pytest.raises(TreebookError, match="top_p"): sample_trees(2, model=str(tmp_path / "s" / "best.pt"), top_p=0)


def test_window_and_ends(data, tmp_path):
    "A run with a window and ends resumes exactly, says so in its checkpoint, and may start from a model without them."
    kw = {**TINY, "window": 8, "ends": True}
    with pytest.raises(TreebookError, match="only with a window"): train(data, tmp_path / "o", **{**TINY, "ends": True})
    full = train(data, tmp_path / "full", **kw)
    part = train(data, tmp_path / "part", stop_after=3, **kw)
    assert same(full["model"].state_dict(), train(data, tmp_path / "part", resume=True, **kw)["model"].state_dict())
    with pytest.raises(TreebookError, match="other settings"): train(data, tmp_path / "part", resume=True, **TINY)
    ck = torch.load(tmp_path / "full" / "last.pt", weights_only=True)
    assert ck["args"]["ends"] is True and ck["config"]["ends"] is True
    plain = train(data, tmp_path / "plain", **TINY)                 # no window: the same weights fit
    more = train(data, tmp_path / "more", init=str(tmp_path / "plain" / "best.pt"), **kw)
    assert more["model"].config.ends and more["step"] == 8
    with pytest.raises(TreebookError, match="not the one this run trains"):
        train(data, tmp_path / "wide", init=str(tmp_path / "plain" / "best.pt"), **{**kw, "dim": 64})
