"""scripts/partnet.py train: --patch-term with --freeze-init trains the patch term alone; their misuse stops with a clear message;
an evaluation of --init weights (--steps 0) leaves no checkpoint behind to shadow the next one; --test-seed and the
scores per scan that an evaluation records; --init weights with a pair context start a run without it."""
import json, shutil, subprocess, sys
from pathlib import Path
import numpy as np, pytest, torch
from treebook.partnet import PairContext

ROOT = Path(__file__).resolve().parent.parent
SMALL = ["--points", "512", "--pool-points", "512", "--width", "8", "--batch", "2", "--train-per-species", "1", "--test-per-species", "1",
         "--threads", "1", "--train-only", "--every", "1"]


def run(*args):
    return subprocess.run([sys.executable, str(ROOT / "scripts" / "partnet.py"), "train", *args], capture_output=True, text=True, timeout=600)


def pools_in(work, name):
    "A fresh --work beside the base one, holding only its scan pools (no checkpoint)."
    (work / name).mkdir()
    for f in ("train_pool.npz", "test_pool.npz"): shutil.copy(work / "base" / f, work / name / f)
    return work / name


@pytest.fixture(scope="module")
def base(tmp_path_factory):
    "A tiny network trained for two steps, saved as --init weights (its work dir holds the scan pools, reused below)."
    work = tmp_path_factory.mktemp("partnet")
    r = run(*SMALL, "--steps", "2", "--work", str(work / "base"))
    assert r.returncode == 0, r.stderr[-2000:]
    blob = torch.load(work / "base" / "checkpoint.pt", weights_only=False)
    init = work / "init.pt"
    torch.save(dict(config=blob["config"], state=blob["model"]), init)
    return work, init


def test_freeze_init_trains_the_patch_term_alone(base):
    work, init = base
    r = run(*SMALL, "--steps", "3", "--lr", "1e-2", "--work", str(pools_in(work, "patch")), "--init", str(init), "--patch-term", "--freeze-init")
    assert r.returncode == 0, r.stderr[-2000:]
    assert "the only layers trained" in r.stdout
    before = torch.load(init, weights_only=False)["state"]
    after = torch.load(work / "patch" / "checkpoint.pt", weights_only=False)["model"]
    new = [k for k in after if k not in before]
    assert new and all(k.startswith("patch.") for k in new)
    assert all(torch.equal(before[k], after[k]) for k in before)                       # every loaded weight as it was
    assert after["patch.head.1.weight"].abs().sum() > 0                                # the patch term left zero: it trained


def test_freeze_init_misuse(base):
    work, init = base
    r = run(*SMALL, "--steps", "1", "--work", str(work / "x"), "--freeze-init")
    assert r.returncode != 0 and "--freeze-init needs --init" in r.stderr
    r = run(*SMALL, "--steps", "1", "--work", str(work / "base"), "--init", str(init), "--freeze-init")
    assert r.returncode != 0 and "nothing would train" in r.stderr


def test_evaluating_init_weights_leaves_no_checkpoint(base):
    work, init = base
    r = run(*SMALL, "--steps", "0", "--work", str(pools_in(work, "ev")), "--init", str(init))
    assert r.returncode == 0, r.stderr[-2000:]
    assert "started from" in r.stdout and not (work / "ev" / "checkpoint.pt").exists()   # a second --init here is read, not shadowed
    r = run(*SMALL, "--steps", "2", "--work", str(work / "base"), "--init", str(init))   # a checkpoint there: it wins, and says so
    assert r.returncode == 0 and "resumed at step 2" in r.stdout and "is not read" in r.stdout


def test_test_seed_makes_other_scans_and_a_cached_pool_is_checked(base):
    work, init = base
    r = run(*SMALL, "--steps", "0", "--work", str(pools_in(work, "seed5")), "--test-seed", "5")
    assert r.returncode != 0 and "holds the scans of seed 999, not 5" in r.stderr     # the pool cached there is another seed's
    r = run(*SMALL, "--steps", "0", "--work", str(work / "fresh5"), "--test-seed", "5")   # --train-only: makes the pools, trains nothing
    assert r.returncode == 0, r.stderr[-2000:]
    with np.load(work / "fresh5" / "test_pool.npz") as z, np.load(work / "base" / "test_pool.npz") as b:
        assert int(z["seed"]) == 5 and int(b["seed"]) == 999
        assert z["points"].shape == b["points"].shape and not np.allclose(z["points"], b["points"])


def test_evaluation_records_each_scan(base):
    work, init = base
    out, res = work / "ev2" / "w.pt", work / "ev2" / "r.json"
    args = [x for x in SMALL if x != "--train-only"]
    r = run(*args, "--steps", "0", "--work", str(pools_in(work, "ev2")), "--init", str(init), "--out", str(out), "--results", str(res))
    assert r.returncode == 0, r.stderr[-2000:]
    rec = json.loads(res.read_text())
    for k in ("aff_f1", "f1", "nmi"):   # one score per held-out scan, whose mean is the record's
        assert len(rec["per_scan"][k]) == rec["test_scans"] == 6
        assert abs(np.mean(rec["per_scan"][k]) - rec["metrics"][k]) < 1e-4
    assert out.exists() and not (out.parent / "partnet.md").exists()   # only weights named partnet.pt get a card


def test_init_leaves_a_pair_context_out(base):
    "Weights with a pair context (scripts/partnet.py pair-context) can start a run: the context fits the old network, so it is dropped."
    work, init = base
    blob = torch.load(init, weights_only=False)
    cfg = dict(blob["config"], pair_context=True)
    state = {**blob["state"], **{f"context.{k}": v for k, v in PairContext().state_dict().items()}}
    torch.save(dict(config=cfg, state=state), work / "init_ctx.pt")
    r = run(*SMALL, "--steps", "1", "--work", str(pools_in(work, "ctxinit")), "--init", str(work / "init_ctx.pt"))
    assert r.returncode == 0, r.stderr[-2000:]
    assert "its pair context is left out" in r.stdout and "fresh: nothing" in r.stdout
