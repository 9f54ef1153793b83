"""scripts/partnet.py soup: the mean of runs' weights, saved as weights that load; runs of different networks refused."""
import subprocess, sys
from pathlib import Path
import torch

ROOT = Path(__file__).resolve().parent.parent
from treebook.partnet import PartNetConfig, TreePartNet, load_partnet, save_partnet


def soup(*args):
    return subprocess.run([sys.executable, str(ROOT / "scripts" / "partnet.py"), "soup", *map(str, args)], capture_output=True, text=True, timeout=300)


def test_soup_is_the_mean(tmp_path):
    runs = []
    for k, threshold in enumerate((0.44, 0.5)):   # the threshold may differ: the soup's is chosen again when it is scored
        torch.manual_seed(k)
        runs.append(save_partnet(TreePartNet(PartNetConfig(width=8, threshold=threshold)), tmp_path / f"r{k}.pt"))
    r = soup(tmp_path / "soup.pt", *runs)
    assert r.returncode == 0, r.stderr[-2000:]
    got, a, b = (load_partnet(p).state_dict() for p in (tmp_path / "soup.pt", *runs))
    assert all(torch.allclose(got[k], (a[k] + b[k]) / 2) for k in got)
    assert any(not torch.equal(a[k], b[k]) for k in a)    # two different runs, so the mean is neither
    ck = tmp_path / "checkpoint.pt"                          # a partnet.py train checkpoint is read as well
    torch.save(dict(model=b, config=load_partnet(runs[1]).cfg.to_dict(), opt={}, step=3), ck)
    r = soup(tmp_path / "soup2.pt", runs[0], ck)
    assert r.returncode == 0, r.stderr[-2000:]
    assert all(torch.allclose(load_partnet(tmp_path / "soup2.pt").state_dict()[k], got[k]) for k in got)


def test_soup_refuses_other_networks(tmp_path):
    a = save_partnet(TreePartNet(PartNetConfig(width=8)), tmp_path / "a.pt")
    b = save_partnet(TreePartNet(PartNetConfig(width=16)), tmp_path / "b.pt")
    r = soup(tmp_path / "soup.pt", a, b)
    assert r.returncode != 0 and "different configs" in r.stderr and not (tmp_path / "soup.pt").exists()
    r = soup(tmp_path / "soup.pt", a)
    assert r.returncode != 0 and "Usage" in r.stderr
