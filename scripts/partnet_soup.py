"""Average the weights of TreePartNet runs that went on from one starting point (a "model soup", Wortsman et al. 2022).

Usage: python scripts/partnet_soup.py OUT.pt RUN1.pt RUN2.pt [...]

Each RUN is a file that treebook.partnet.save_partnet wrote (train_partnet.py's --out) or a checkpoint of train_partnet.py
(its --work's checkpoint.pt, or one that scripts/gpu.sh partnet returned). They must share one config, up to the
merging threshold, linkage and test-time turns, which are taken from the first: score the soup with
train_partnet.py --init OUT.pt --steps 0, which chooses them again on the training scans. OUT's meta names the runs it averages.
"""
import sys
from dataclasses import replace
from pathlib import Path
import torch

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))
from treebook.partnet import PartNetConfig, TreePartNet, load_partnet, save_partnet


def load_run(path) -> TreePartNet:
    "The network in `path`: saved weights, or a train_partnet.py checkpoint (its `model` and `config`)."
    blob = torch.load(path, map_location="cpu", weights_only=False)
    if isinstance(blob, dict) and "model" in blob and "config" in blob:
        model = TreePartNet(PartNetConfig.from_dict(blob["config"])); model.load_state_dict(blob["model"]); return model
    return load_partnet(path)


def soup(out, runs):
    models = [load_run(r) for r in runs]
    same = lambda c: replace(c, threshold=0.5, linkage="closure", tta=1)   # how it is used, not what it is
    if any(same(m.cfg) != same(models[0].cfg) for m in models): sys.exit("these runs have different configs: only runs of one network average")
    avg = TreePartNet(models[0].cfg)
    states = [m.state_dict() for m in models]
    avg.load_state_dict({k: torch.stack([s[k].float() for s in states]).mean(0).to(states[0][k].dtype) for k in states[0]})
    save_partnet(avg, out, soup_of=[str(r) for r in runs])
    print(f"wrote {out}: the mean of {len(runs)} runs' weights")


if __name__ == "__main__":
    if len(sys.argv) < 4: sys.exit(__doc__)
    soup(sys.argv[1], sys.argv[2:])
