"""The elm's hourglass (Full, width 128, depth 8, 4 heads) at the lengths of the larger species: CPU time and peak
memory of a training step at 1,616, 3,200 and 6,400 tokens (batch 1 and 2), with full causal attention in the two
full-resolution layers and with a window there (ModelConfig.window), the share of the step the full-resolution
attention takes, and sampling one and 16 trees of 6,416 tokens (an untrained model; the length is forced). Writes
results/hourglass_long.json. With --with-ends each window also runs with ModelConfig.ends (the windowed layers also
see every earlier branch's last token; "128+e" in the table):

    nice -n 19 .venv/bin/python benchmarks/hourglass_long.py --lengths 3200 6400 --windows 0 128 --batches 2 \
        --with-ends --out results/hourglass_ends.json

    nice -n 19 .venv/bin/python benchmarks/hourglass_long.py            # about 4 minutes on 2 shared cores
    .venv/bin/python benchmarks/hourglass_long.py --quick               # toy sizes, to check the script

Method as benchmarks/hourglass.py (whose PeakRSS it uses): one torch thread, CPU time of that thread
(time.thread_time), each (length, batch, window) in a fresh subprocess with MALLOC_MMAP_THRESHOLD_=65536, peak RSS
above the baseline after a warm-up step. `fwd_bwd_s` is forward + backward, `step_s` adds AdamW; `attention_s` is
one full-resolution attention alone (scaled_dot_product_attention or window_attention, forward + backward) on
random (batch, heads, length, dim / heads) inputs, and `attention_share` is twice that (two such layers) over
`fwd_bwd_s`.
"""
import argparse, gc, json, os, subprocess, sys, time
from pathlib import Path
sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "scripts"))
import provenance   # scripts/provenance.py
from hourglass import PeakRSS, machine, rss_mb   # benchmarks/hourglass.py, beside this script

ROOT = Path(__file__).resolve().parent.parent


def median(xs): xs = sorted(xs); n = len(xs); return xs[n // 2] if n % 2 else (xs[n // 2 - 1] + xs[n // 2]) / 2


def worker(a):
    import torch, torch.nn.functional as F
    from treebook.hourglass import ModelConfig, TreeTransformer, window_attention
    torch.set_num_threads(1); torch.manual_seed(0)
    c = ModelConfig(arch="full", dim=a.dim, depth=a.depth, heads=a.heads, max_len=a.length + 16, window=a.window,
                    ends=bool(a.ends))
    m = TreeTransformer(c); opt = torch.optim.AdamW(m.parameters(), lr=1e-4)
    def step(L, B, out=None):
        x = torch.randint(0, 256, (B, L + 1)); c0 = time.thread_time()
        F.cross_entropy(m(x[:, :-1]).flatten(0, 1), x[:, 1:].flatten()).backward(); c1 = time.thread_time()
        opt.step(); opt.zero_grad(set_to_none=True)
        if out is not None: out.append((c1 - c0, time.thread_time() - c0))
    step(64, 1); gc.collect()                              # warm-up: AdamW's state, kernels
    base, times, peaks = rss_mb(), [], []
    for _ in range(a.steps):
        with PeakRSS() as pk: step(a.length, a.batch, times)
        peaks.append(pk.peak - base); gc.collect()
    att = []
    for _ in range(a.steps):
        q, k, v = (torch.randn(a.batch, a.heads, a.length, a.dim // a.heads, requires_grad=True) for _ in range(3))
        c0 = time.thread_time()
        y = (window_attention(q, k, v, a.window, ends=bool(a.ends)) if a.window else
             F.scaled_dot_product_attention(q, k, v, is_causal=True))
        y.sum().backward(); att.append(time.thread_time() - c0)
    fb = median([t for t, _ in times])
    print(json.dumps(dict(length=a.length, batch=a.batch, window=a.window, ends=bool(a.ends), fwd_bwd_s=fb, step_s=median([s for _, s in times]),
                          times=times, peak_mb=max(peaks), baseline_mb=base, attention_s=median(att),
                          attention_share=2 * median(att) / fb, params=m.n_params)))


def run_worker(a, **kw):
    cmd = [sys.executable, __file__, "--worker"] + [f"--{k}={v}" for k, v in kw.items()] + \
          [f"--dim={a.dim}", f"--depth={a.depth}", f"--heads={a.heads}", f"--steps={a.steps}"]
    out = subprocess.run(cmd, env=dict(os.environ, MALLOC_MMAP_THRESHOLD_="65536", OMP_NUM_THREADS="1"),
                         capture_output=True, text=True, cwd=ROOT)
    if out.returncode: raise RuntimeError(out.stderr[-3000:])
    return json.loads(out.stdout.strip().splitlines()[-1])


def sampling(a, window, ends=False):
    "CPU seconds to sample 1 and 16 sequences of `a.sample_len` tokens (forced length) from an untrained model."
    import torch
    from types import SimpleNamespace
    from treebook.hourglass import ModelConfig, TreeTransformer
    from treebook.sampling import CONTRACT, sample
    torch.set_num_threads(1); torch.manual_seed(0)
    m = TreeTransformer(ModelConfig(arch="full", dim=a.dim, depth=a.depth, heads=a.heads, max_len=a.sample_len,
                                    window=window, ends=ends)).eval()
    tok = SimpleNamespace(**vars(CONTRACT), root_tokens=(128, 128, 0), min_radius_token=1)
    L, res = a.sample_len, {"window": window, "ends": ends, "sample_len": a.sample_len}
    for n in (1, 16):
        c0, t0 = time.thread_time(), time.perf_counter()
        out = sample(m, n, tok=tok, max_len=L, min_len=L, seed=0)
        assert all(len(s) == L for s in out), [len(s) for s in out]
        res[f"n{n}_s"], res[f"n{n}_wall_s"] = time.thread_time() - c0, time.perf_counter() - t0
        print(f"sampled {n} x {L} tokens, window {window}{'+e' * ends}: {res[f'n{n}_s']:.1f} s CPU", flush=True)
    return res


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--worker", action="store_true", help=argparse.SUPPRESS)
    for k, v in dict(length=1616, batch=1, window=0, ends=0, steps=3, dim=128, depth=8, heads=4,
                     sample_len=6416).items():
        p.add_argument(f"--{k.replace('_', '-')}", type=int, default=v)
    p.add_argument("--lengths", type=int, nargs="+", default=[1616, 3200, 6400])
    p.add_argument("--windows", type=int, nargs="+", default=[0, 128, 256])
    p.add_argument("--batches", type=int, nargs="+", default=[1, 2])
    p.add_argument("--quick", action="store_true"); p.add_argument("--out", default="results/hourglass_long.json")
    p.add_argument("--with-ends", action="store_true", help="each window also with ModelConfig.ends")
    a = p.parse_args()
    if a.worker: return worker(a)
    if a.quick: a.dim, a.depth, a.heads, a.lengths, a.windows, a.steps, a.sample_len = 32, 5, 2, [64, 160], [0, 16], 1, 160
    import torch
    kinds = [(w, e) for w in a.windows for e in ((0, 1) if a.with_ends and w else (0,))]
    t_start, load0, rows = time.time(), os.getloadavg(), []
    for L in a.lengths:
        for B in a.batches:
            for w, e in kinds:
                rows.append(run_worker(a, length=L, batch=B, window=w, ends=e)); r = rows[-1]
                print(f"{L} x {B}, window {w}{'+e' * e}: fwd+bwd {r['fwd_bwd_s']:.2f} s, step {r['step_s']:.2f} s, "
                      f"{r['peak_mb']:.0f} MiB, attention {r['attention_share']:.0%}", flush=True)
    samp = [sampling(a, w, bool(e)) for w, e in kinds[:1] + kinds[-1:]]
    get = lambda L, B, w: next(r for r in rows if (r["length"], r["batch"], r["window"]) == (L, B, w))
    name = lambda r: f"{r['window']}{'+e' * r.get('ends', False)}" if r["window"] else "all"
    table = [f"{'L x B':>10} {'window':>6} {'fwd+bwd s':>9} {'step s':>7} {'ms/token':>8} {'peak MiB':>8} "
             f"{'attention':>9} {'speed-up':>8}"]
    for r in rows:
        full = get(r["length"], r["batch"], 0)
        table.append(f"{r['length']:>5} x {r['batch']:<2} {name(r):>6} {r['fwd_bwd_s']:9.2f} {r['step_s']:7.2f} "
                     f"{1e3 * r['step_s'] / (r['length'] * r['batch']):8.3f} {r['peak_mb']:8.0f} "
                     f"{r['attention_share']:9.0%} {full['fwd_bwd_s'] / r['fwd_bwd_s']:7.2f}x")
    for s in samp:
        table.append(f"sampling {s['sample_len']} tokens, window {name(s)}: one tree {s['n1_s']:.1f} s, "
                     f"16 trees {s['n16_s']:.1f} s (CPU, one thread)")
    res = dict(torch=torch.__version__, machine_detail=machine(), threads=1,
               config=dict(arch="full", dim=a.dim, depth=a.depth, heads=a.heads), loadavg_start=load0,
               method=__doc__.split("Method as ", 1)[1].strip(), train=rows, sampling=samp, table=table)
    res["loadavg_end"], res["wall_s"] = os.getloadavg(), time.time() - t_start
    provenance.record("benchmarks/hourglass_long.py", res, a.out, threads=1, torch=torch.__version__)
    print("\n".join(table))


if __name__ == "__main__":
    main()
