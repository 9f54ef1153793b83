"""Hourglass vs plain transformer on the CPU: training-step time and peak memory against sequence length, and sampling
speed with and without the key/value cache. Writes results/hourglass.json and results/hourglass.png.

    .venv/bin/python benchmarks/hourglass.py            # the full run (about 20-30 minutes on 2 cores)
    .venv/bin/python benchmarks/hourglass.py --quick    # a smoke test at toy sizes

Every measurement of a training step runs in a fresh subprocess, PT and Full alternating, so neither inherits the
other's heap. Time: the two cores of this machine are shared with other jobs (load averages above 10 were seen), so
wall-clock times swing by 2-5x from one step to the next. The run therefore uses one torch thread and takes as its
main figure the CPU time of that thread (time.thread_time: torch with one thread computes forward, backward and the
optimizer step in the calling thread), which does not count the time the thread waits for a core; wall-clock
times are recorded beside it. Memory: the subprocess runs with MALLOC_MMAP_THRESHOLD_ fixed at 64 KiB, so glibc hands every tensor's
memory back to the system when it is freed and the resident set size (RSS) follows the live tensors; after one
warm-up step (which creates AdamW's state) and freeing the gradients, the RSS is the baseline (weights + optimizer
state + interpreter), and a thread reading /proc/self/statm every millisecond records the peak during the timed steps.
`peak_mb` is that peak minus the baseline: activations, gradients and temporaries. tracemalloc cannot see torch's
allocations, hence RSS.
"""
import argparse, gc, json, os, platform, resource, subprocess, sys, threading, time
from pathlib import Path
sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "scripts"))
import provenance   # scripts/provenance.py

ROOT = Path(__file__).resolve().parent.parent
PAGE = os.sysconf("SC_PAGE_SIZE")


def rss_mb():
    with open("/proc/self/statm") as f: return int(f.read().split()[1]) * PAGE / 2**20


class PeakRSS:
    "Sample the RSS every `dt` seconds in a thread; `.peak` is the largest seen."
    def __init__(self, dt=0.001): self.dt, self.peak, self._stop = dt, rss_mb(), threading.Event()
    def __enter__(self):
        self.t = threading.Thread(target=self._run, daemon=True); self.t.start(); return self
    def _run(self):
        while not self._stop.is_set(): self.peak = max(self.peak, rss_mb()); time.sleep(self.dt)
    def __exit__(self, *a): self._stop.set(); self.t.join(); self.peak = max(self.peak, rss_mb())


def worker_train(a):
    import torch, torch.nn.functional as F
    from treebook.hourglass import ModelConfig, TreeTransformer
    torch.set_num_threads(a.threads); torch.manual_seed(0)
    m = TreeTransformer(ModelConfig(arch=a.arch, dim=a.dim, depth=a.depth, heads=a.heads, max_len=max(a.length + 8, 8216)))
    opt = torch.optim.AdamW(m.parameters(), lr=1e-4)
    weights_mb = sum(p.numel() * p.element_size() for p in m.parameters()) / 2**20
    def step(L, B):
        x = torch.randint(0, 256, (B, L + 1))
        loss = F.cross_entropy(m(x[:, :-1]).flatten(0, 1), x[:, 1:].flatten())
        loss.backward(); opt.step(); opt.zero_grad(set_to_none=True)
    step(64, 1)                                  # warm-up: AdamW state, kernels
    gc.collect()
    base, times, walls, peaks = rss_mb(), [], [], []
    for _ in range(a.steps):
        with PeakRSS() as pk:
            t0, c0 = time.perf_counter(), time.thread_time(); step(a.length, a.batch)
            times.append(time.thread_time() - c0); walls.append(time.perf_counter() - t0)
        peaks.append(pk.peak - base); gc.collect()
    print(json.dumps(dict(arch=a.arch, length=a.length, batch=a.batch, times=times, walls=walls, peak_mb=max(peaks),
                          threads=torch.get_num_threads(),
                          baseline_mb=base, weights_mb=weights_mb, params=m.n_params,
                          maxrss_mb=resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024)))


def run_worker(args, **kw):
    cmd = [sys.executable, __file__, "--worker"] + [f"--{k}={v}" for k, v in kw.items()] + \
          [f"--dim={args.dim}", f"--depth={args.depth}", f"--heads={args.heads}", f"--steps={args.steps}"]
    env = dict(os.environ, MALLOC_MMAP_THRESHOLD_="65536", OMP_NUM_THREADS=str(args.threads))
    out = subprocess.run(cmd, env=env, capture_output=True, text=True, cwd=ROOT)
    if out.returncode: raise RuntimeError(out.stderr[-3000:])
    return json.loads(out.stdout.strip().splitlines()[-1])


def sampling(args):
    "Time sampling one tree (cached, uncached) and a batch of 16 (cached) from an untrained Full model."
    import torch
    from types import SimpleNamespace
    from treebook.hourglass import ModelConfig, TreeTransformer
    from treebook.sampling import CONTRACT, sample
    torch.manual_seed(0)
    m = TreeTransformer(ModelConfig(arch="full", dim=args.dim, depth=args.depth, heads=args.heads)).eval()
    tok = SimpleNamespace(**vars(CONTRACT), root_tokens=(128, 128, 0), min_radius_token=1)
    L = args.sample_len
    def timed(**kw):
        t0, c0 = time.perf_counter(), time.thread_time()
        out = sample(m, tok=tok, max_len=L, min_len=L, seed=0, **kw)
        dt, wall = time.thread_time() - c0, time.perf_counter() - t0
        assert all(len(s) == L for s in out), [len(s) for s in out]
        print(f"sampled {len(out)} x {L} tokens in {dt:.2f} s CPU ({wall:.2f} s wall)", kw, flush=True)
        return dt, wall
    res = {"sample_len": L, "threads": torch.get_num_threads()}
    sample(m, tok=tok, max_len=64, min_len=64)   # warm-up
    runs = [timed(n=1) for _ in range(args.sample_repeats)]
    res["cached_1_s"], res["cached_1_wall_s"] = [r[0] for r in runs], [r[1] for r in runs]
    res["cached_16_s"], res["cached_16_wall_s"] = map(list, zip(timed(n=16)))
    # Without a cache, step t runs the model on the prefix of t tokens, padded inside to the next multiple of 8, so
    # the 8 steps t = 8g+1 .. 8g+8 cost the same: time one forward pass per group (8g+8 tokens) and count it 8 times.
    x = torch.randint(0, 256, (1, L))
    with torch.no_grad():
        c0, t0, total = time.thread_time(), time.perf_counter(), 0.0
        for g in range(L // 8):
            c1 = time.thread_time(); m(x[:, :8 * g + 8]); total += 8 * (time.thread_time() - c1)
    res["uncached_1_s"], res["uncached_method"] = [total], "one forward pass per group of 8 steps, counted 8 times"
    res["uncached_measured_cpu_s"], res["uncached_measured_wall_s"] = time.thread_time() - c0, time.perf_counter() - t0
    return res


def machine():
    cpu = next((l.split(":", 1)[1].strip() for l in open("/proc/cpuinfo") if l.startswith("model name")), platform.processor())
    mem = next((l.split()[1] for l in open("/proc/meminfo") if l.startswith("MemTotal")), "0")
    return f"{cpu}, {os.cpu_count()} cores, {int(mem) / 2**20:.0f} GiB RAM, {platform.system()} {platform.release()}"


def plot(res, path):
    import matplotlib; matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, axs = plt.subplots(1, 2, figsize=(10, 4))
    for arch, st in (("pt", "o-"), ("full", "s-")):
        rows = sorted((r for r in res["train"] if r["arch"] == arch and r["batch"] == 1), key=lambda r: r["length"])
        Ls = [r["length"] for r in rows]
        axs[0].plot(Ls, [r["time_median_s"] for r in rows], st, label={"pt": "plain transformer", "full": "hourglass (Full)"}[arch])
        axs[1].plot(Ls, [r["peak_mb"] for r in rows], st, label={"pt": "plain transformer", "full": "hourglass (Full)"}[arch])
    for ax, yl in zip(axs, ("training step (s, CPU time of one thread)", "peak memory above weights + AdamW state (MiB)")):
        ax.set_xscale("log"); ax.set_yscale("log"); ax.set_xlabel("sequence length (tokens), batch 1"); ax.set_ylabel(yl)
        ax.grid(True, which="both", alpha=0.3); ax.legend()
    fig.suptitle(f"width {res['config']['dim']}, depth {res['config']['depth']}, {res['threads']} CPU threads")
    fig.tight_layout(); fig.savefig(path, dpi=110); plt.close(fig)


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--worker", action="store_true", help=argparse.SUPPRESS)
    p.add_argument("--arch", default="full"); p.add_argument("--length", type=int, default=1616)
    p.add_argument("--batch", type=int, default=4); p.add_argument("--steps", type=int, default=2)
    p.add_argument("--dim", type=int, default=256); p.add_argument("--depth", type=int, default=24)
    p.add_argument("--heads", type=int, default=8); p.add_argument("--threads", type=int, default=1)
    p.add_argument("--repeats", type=int, default=1, help="fresh processes per (arch, length)")
    p.add_argument("--lengths", type=int, nargs="+", default=[408, 816, 1616, 3216, 8216])
    p.add_argument("--sample-len", type=int, default=1616); p.add_argument("--sample-repeats", type=int, default=2)
    p.add_argument("--skip-sampling", action="store_true"); p.add_argument("--skip-train", action="store_true")
    p.add_argument("--quick", action="store_true", help="toy sizes, to check the script")
    p.add_argument("--out", default="results/hourglass.json")
    a = p.parse_args()
    if a.worker: return worker_train(a)
    import torch
    torch.set_num_threads(a.threads)
    if a.quick: a.dim, a.depth, a.heads, a.lengths, a.repeats, a.steps, a.sample_len = 32, 8, 2, [64, 128], 1, 1, 64
    cases = [] if a.skip_train else [(1616 if not a.quick else 128, 4)] + [(L, 1) for L in a.lengths]
    t_start, load0 = time.time(), os.getloadavg()
    train = []
    for L, B in cases:
        runs = {"pt": [], "full": []}
        for r in range(a.repeats):
            for arch in ("pt", "full") if r % 2 == 0 else ("full", "pt"):
                runs[arch].append(run_worker(a, arch=arch, length=L, batch=B))
                print(arch, L, B, [round(t, 2) for t in runs[arch][-1]["times"]], f"{runs[arch][-1]['peak_mb']:.0f} MiB", flush=True)
        for arch, rs in runs.items():
            ts = sorted(t for r in rs for t in r["times"])
            train.append(dict(arch=arch, length=L, batch=B, times_s=ts, walls_s=[w for r in rs for w in r["walls"]],
                              threads=rs[0]["threads"], time_median_s=ts[len(ts) // 2] if len(ts) % 2 else
                              (ts[len(ts) // 2 - 1] + ts[len(ts) // 2]) / 2, time_min_s=ts[0],
                              peak_mb=max(r["peak_mb"] for r in rs), baseline_mb=rs[0]["baseline_mb"],
                              weights_mb=rs[0]["weights_mb"], params=rs[0]["params"]))
    get = lambda arch, L, B: next(r for r in train if (r["arch"], r["length"], r["batch"]) == (arch, L, B))
    ratios = []
    for L, B in cases:
        pt, fu = get("pt", L, B), get("full", L, B)
        ratios.append(dict(length=L, batch=B, speedup_median=pt["time_median_s"] / fu["time_median_s"],
                           speedup_min=pt["time_min_s"] / fu["time_min_s"], memory_ratio=pt["peak_mb"] / fu["peak_mb"]))
    res = dict(command=" ".join(["python"] + sys.argv), commit=provenance.commit(), machine=machine(), torch=torch.__version__,
               threads=a.threads, started=time.strftime("%Y-%m-%d %H:%M:%S", time.localtime(t_start)),
               loadavg_start=load0, config=dict(dim=a.dim, depth=a.depth, heads=a.heads),
               memory_method=__doc__.split("Memory: ", 1)[1].strip(), train=train, ratios=ratios)
    if not a.skip_sampling:
        s = sampling(a)
        s["cached_speedup"] = min(s["uncached_1_s"]) / min(s["cached_1_s"])
        res["sampling"] = s
    res["loadavg_end"], res["wall_s"] = os.getloadavg(), time.time() - t_start
    big = (8216 if not a.quick else a.lengths[-1], 1)
    goals = {}
    if ratios:
        r1616 = ratios[0]; rbig = next(r for r in ratios if (r["length"], r["batch"]) == big)
        goals = {"train 1616x4: Full >= 5x faster than PT": r1616["speedup_median"] >= 5,
                 "train 1616x4: Full >= 3x less peak memory": r1616["memory_ratio"] >= 3,
                 "train 8216x1: Full >= 12x faster than PT": rbig["speedup_median"] >= 12}
    if "sampling" in res:
        s = res["sampling"]
        goals.update({"sampling: cached >= 10x faster than uncached": s["cached_speedup"] >= 10,
                      "sampling: one tree <= 3 s": min(s["cached_1_s"]) <= 3, "sampling: batch of 16 <= 15 s": min(s["cached_16_s"]) <= 15})
    res["goals"] = goals
    table = [f"{'LxB':>12} {'PT s':>8} {'Full s':>8} {'speedup':>8} {'PT MiB':>8} {'Full MiB':>9} {'mem ratio':>9}"]
    for (L, B), r in zip(cases, ratios):
        pt, fu = get("pt", L, B), get("full", L, B)
        table.append(f"{f'{L}x{B}':>12} {pt['time_median_s']:8.2f} {fu['time_median_s']:8.2f} {r['speedup_median']:7.1f}x "
                     f"{pt['peak_mb']:8.0f} {fu['peak_mb']:9.0f} {r['memory_ratio']:8.1f}x")
    if "sampling" in res:
        s = res["sampling"]
        table.append(f"sampling {s['sample_len']} tokens (Full, width {a.dim}, depth {a.depth}): cached {min(s['cached_1_s']):.2f} s, uncached {min(s['uncached_1_s']):.1f} s "
                     f"({s['cached_speedup']:.0f}x), batch of 16 cached {min(s['cached_16_s']):.2f} s")
    res["table"] = table
    out = ROOT / a.out
    out.parent.mkdir(exist_ok=True)
    tmp = out.with_suffix(".json.part"); tmp.write_text(json.dumps(res, indent=1)); os.replace(tmp, out)
    if train: plot(res, out.with_suffix(".png"))
    print("\n".join(table)); print(json.dumps(goals, indent=1))


if __name__ == "__main__":
    main()
