"""Evaluate a trained elm run on the held-out split and ship it: weights, tokenizer and model card into the package.

Usage: python scripts/ship_elm.py --run runs/elm --data data/elm [--n-samples 1000] [--no-ship]
Writes results/elm_eval.json (command, commit, machine, metrics: metrics.sample_scores) and, unless --no-ship,
treebook/data/weights/elm.{pt,tok.json,md} (the card: train.elm_card) and results/elm_loss.png.
"""
import argparse, json, multiprocessing, shutil, time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path
import provenance   # scripts/provenance.py, beside this script
import numpy as np, torch
from tqdm.auto import tqdm
from treebook.datasets import load_trees, load_manifest
from treebook.hourglass import TreeTransformer
from treebook.tokens import Tokenizer
from treebook.sampling import sample
from treebook.train import perplexity, elm_card, WEIGHTS
from treebook.metrics import tree_clouds, evaluate, fpd, load_species_pointnet, quality_targets, sample_scores

_W = {}
def _init(run, ckpt="best.pt"):
    torch.set_num_threads(1)   # one thread for each sampling process
    _W["net"], _W["tok"] = TreeTransformer.load(Path(run) / ckpt), Tokenizer.load(Path(run) / "tokenizer.json")
def _draw(job):
    seed, n, structure, t, top_p = job
    return sample(_W["net"], n, tok=_W["tok"], temperature=t, top_p=top_p, structure=structure, min_len=24, seed=seed)

if __name__ == "__main__":
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    for k, v in dict(run="runs/elm", data="data/elm", n_samples=1000, n_connect=100, batch=50, seed=0, temperature=0.9,
                     top_p=0.95, threads=2, workers=2, limit=None, ckpt="best.pt", out_json="results/elm_eval.json").items():
        p.add_argument(f"--{k.replace('_', '-')}", default=v, type=int if k == "limit" else type(v))
    p.add_argument("--no-ship", action="store_true"); a = p.parse_args()
    torch.set_num_threads(a.threads); run = Path(a.run)
    net, tok = TreeTransformer.load(run / a.ckpt), Tokenizer.load(run / "tokenizer.json")
    ck, state = torch.load(run / a.ckpt, weights_only=True)["meta"], torch.load(run / "last.pt", weights_only=True)
    test, train = load_trees(a.data, "test"), load_trees(a.data, "train")
    if a.limit: test, train = test[:a.limit], train[:a.limit]  # a smoke test only
    res = {"run": {"best_step": ck["step"], "last_step": state["step"], "train_seconds": state.get("seconds"), "args": state["args"],
                   "n_params": net.n_params},
           "data": {"folder": a.data, "train": len(train), "test": len(test), "manifest_seed": load_manifest(a.data)["config"]["seed"]},
           "sampling": {"n": a.n_samples, "temperature": a.temperature, "top_p": a.top_p, "seed": a.seed}}
    t = time.time(); ppl = perplexity(net, tok.encode_batch(test, "dfs"), batch_size=8, progress=True)
    res |= {"PPL": ppl["ppl"], "val_loss": ppl["loss"], "seconds_ppl": time.time() - t}; t = time.time()
    jobs = [(i, min(a.batch, a.n_samples - i), True) for i in range(0, a.n_samples, a.batch)]
    jobs += [(10**6 + i, min(a.batch, a.n_connect - i), False) for i in range(0, a.n_connect, a.batch)]
    with ProcessPoolExecutor(a.workers, mp_context=multiprocessing.get_context("spawn"), initializer=_init, initargs=(str(run), a.ckpt)) as ex:
        done = list(tqdm(ex.map(_draw, [(a.seed + i, n, st, a.temperature, a.top_p) for i, n, st in jobs]), total=len(jobs), desc="sampling"))
    seqs, free = ([s for (_, _, st), d in zip(jobs, done) if st == want for s in d] for want in (True, False))
    res["seconds_sampling"], t, R, T, pn = time.time() - t, time.time(), tree_clouds(test, seed=2), tree_clouds(train, seed=3), load_species_pointnet()
    sc = sample_scores(seqs, free, tok, R, T, pn)
    res |= {k: sc[k] for k in ("Connect_structure", "Connect_free")} | {"empty_samples": a.n_samples - len(sc["trees"]),
            "branches_mean": float(np.mean([g.n for g in sc["trees"]])), "scores": sc["scores"]}
    res["reference_train_vs_test"] = evaluate(T[:len(R)], R) | {"FPD": fpd(T[:len(R)], R, pn)}
    res["seconds_metrics"] = time.time() - t; res["targets"] = quality_targets(res)
    res = provenance.record("scripts/ship_elm.py", res, a.out_json, threads=a.threads, torch=torch.__version__); print(json.dumps(res, indent=1))
    if not a.no_ship:
        shutil.copyfile(run / "loss.png", provenance.ROOT / "results" / "elm_loss.png")  # the log itself stays in the run
        shutil.copyfile(run / a.ckpt, WEIGHTS / "elm.pt"); shutil.copyfile(run / "tokenizer.json", WEIGHTS / "elm.tok.json")
        (WEIGHTS / "elm.md").write_text(card := elm_card(res, net.config.max_len, a.batch, a.n_connect)); print(card)
