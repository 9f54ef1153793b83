"""scripts/partnet.py pair-context: it gives weights a pair context and leaves the network as it was, scores every test set with and
without it from one run of the network, replaces a pair context the weights already hold, and stops on a bad flag."""
import json, subprocess, sys
from pathlib import Path
import pytest, torch
from treebook.partnet import PartNetConfig, TreePartNet, load_partnet, save_partnet

ROOT = Path(__file__).resolve().parent.parent
TINY = ["--per-species", "2", "--fit-scans", "6", "--tests", "999:1", "--epochs", "2", "--threads", "1"]


def run(*args):
    return subprocess.run([sys.executable, str(ROOT / "scripts" / "partnet.py"), "pair-context", *args], capture_output=True, text=True, timeout=600)


@pytest.fixture(scope="module")
def done(tmp_path_factory):
    "A small untrained network, given a pair context by the script."
    d = tmp_path_factory.mktemp("context")
    torch.manual_seed(0)
    save_partnet(TreePartNet(PartNetConfig(n_points=512, width=8, n1=64, n2=32, threshold=0.4, linkage="closure")), d / "net.pt")
    r = run(*TINY, "--weights", str(d / "net.pt"), "--work", str(d / "work"), "--out", str(d / "ctx.pt"), "--results", str(d / "ctx.json"))
    assert r.returncode == 0, r.stderr[-2000:]
    return d


def test_record_and_weights(done):
    rec = json.loads((done / "ctx.json").read_text())
    assert set(rec["tests"]) == {"999x1"} and set(rec["tests"]["999x1"]) == {"network", "with context"}
    for row in rec["tests"]["999x1"].values():
        assert len(row["per_scan"]["aff_f1"]) == 6 and 0 <= row["metrics"]["aff_f1"] <= 1
    assert (rec["network_threshold"], rec["network_linkage"], rec["scans"], rec["fit_scans"]) == (0.4, "closure", 12, 6)
    assert set(rec["threshold_fit"]) == set(rec["network_threshold_fit"]) and f"{rec['linkage']}@{rec['threshold']:.2f}" in rec["threshold_fit"]
    net, ctx = load_partnet(done / "net.pt"), load_partnet(done / "ctx.pt")
    assert ctx.cfg.pair_context and not net.cfg.pair_context
    assert (ctx.cfg.threshold, ctx.cfg.linkage) == (rec["threshold"], rec["linkage"])
    theirs = ctx.state_dict()
    assert all(torch.equal(v, theirs[k]) for k, v in net.state_dict().items())      # the network itself is untouched
    assert any(k.startswith("context.") for k in theirs)


def test_a_held_context_is_replaced(done):
    r = run(*TINY, "--weights", str(done / "ctx.pt"), "--work", str(done / "work"), "--out", str(done / "ctx2.pt"), "--results", str(done / "ctx2.json"),
            "--seed", "1")
    assert r.returncode == 0, r.stderr[-2000:]
    a, b = load_partnet(done / "ctx.pt").state_dict(), load_partnet(done / "ctx2.pt").state_dict()
    assert all(torch.equal(a[k], b[k]) for k in a if not k.startswith("context."))
    assert not torch.equal(a["context.net.0.0.weight"], b["context.net.0.0.weight"])  # a new one, from another seed


def test_bad_flags(done):
    for bad in ("999-10", "999:0", "999:1:2"):
        r = run("--tests", bad)
        assert r.returncode == 2 and "SEED:PER_SPECIES" in r.stderr, bad
    r = run("--fit-scans", "0")
    assert r.returncode == 2 and "at least 1" in r.stderr
    r = run(*TINY, "--fit-scans", "12", "--weights", str(done / "net.pt"), "--work", str(done / "work"))
    assert r.returncode == 2 and "leaves none" in r.stderr


def test_other_weights_are_run_again(done):
    "The network outputs cached in --work carry the network's fingerprint: other weights in the same --work are run, not read back."
    torch.manual_seed(1)
    save_partnet(TreePartNet(PartNetConfig(n_points=512, width=8, n1=64, n2=32, threshold=0.4, linkage="closure")), done / "net2.pt")
    r = run(*TINY, "--weights", str(done / "net2.pt"), "--work", str(done / "work"), "--out", str(done / "ctx3.pt"), "--results", str(done / "ctx3.json"))
    assert r.returncode == 0, r.stderr[-2000:]
    first, other = (json.loads((done / f).read_text())["network"] for f in ("ctx.json", "ctx3.json"))
    assert first != other
    assert torch.load(done / "work" / "test_outs_999_1.pt", weights_only=False)["network"] == other
