"""Table 2's cost columns on a shared machine: time of one training step (forward + backward + AdamW) and peak memory
of each architecture, at the ablation's size and at the shipped model's. Usage: python benchmarks/ablation_cost.py
[--repeats 3] [--threads 1]. Timing is round-robin over the architectures (each repeat times every one once), so that
load from other jobs falls on all alike; the median is reported. Memory: each architecture in a fresh process, peak
resident set (VmHWM, reset just before) during two steps minus the resident set before the first.
Writes results/ablation_cost.json (command, commit, machine)."""
import argparse, json, os, subprocess, sys, time
from pathlib import Path
sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "scripts")); import provenance   # scripts/provenance.py
import numpy as np, torch
from treebook.hourglass import ARCHS, ModelConfig, TreeTransformer

SIZES = {"ablation (L=400, dim 64, depth 6, batch 8)": dict(L=400, dim=64, depth=6, heads=4, batch=8),
         "shipped (L=1616, dim 128, depth 8, batch 4)": dict(L=1616, dim=128, depth=8, heads=4, batch=4)}

def make(arch, s):
    torch.manual_seed(0)
    m = TreeTransformer(ModelConfig(arch=arch, dim=s["dim"], depth=s["depth"], heads=s["heads"], max_len=s["L"]))
    return m, torch.optim.AdamW(m.parameters(), 1e-3), torch.randint(0, 256, (s["batch"], s["L"]))

def step(m, opt, x):
    loss = torch.nn.functional.cross_entropy(m(x[:, :-1]).flatten(0, 1), x[:, 1:].flatten())
    opt.zero_grad(); loss.backward(); opt.step()

def memory(arch, size):
    s = SIZES[size]; m, opt, x = make(arch, s)
    status = lambda key: int(next(l for l in open("/proc/self/status") if l.startswith(key)).split()[1])  # kB
    Path("/proc/self/clear_refs").write_text("5")  # Linux: reset the peak resident set (VmHWM) to the current one
    before = status("VmRSS:")
    for _ in range(2): step(m, opt, x)
    print(json.dumps({"peak_mb": (status("VmHWM:") - before) / 1024}))

def main():
    p = argparse.ArgumentParser(); p.add_argument("--repeats", type=int, default=3); p.add_argument("--threads", type=int, default=1)
    p.add_argument("--_mem", nargs=2, default=None, help=argparse.SUPPRESS)
    a = p.parse_args(); torch.set_num_threads(a.threads)
    if a._mem: return memory(*a._mem)
    out, load = {"sizes": {}}, os.getloadavg()
    for size, s in SIZES.items():
        models = {arch: make(arch, s) for arch in ARCHS}
        for arch in ARCHS: step(*models[arch])  # warm-up
        times = {arch: [] for arch in ARCHS}
        for r in range(a.repeats):
            for arch in ARCHS:
                t = time.perf_counter(); step(*models[arch]); times[arch].append(time.perf_counter() - t)
        rows = {}
        for arch in ARCHS:
            mem = subprocess.run([sys.executable, __file__, "--threads", str(a.threads), "--_mem", arch, size], capture_output=True, text=True)
            rows[arch] = {"step_s_median": float(np.median(times[arch])), "step_s": times[arch], "n_params": models[arch][0].n_params,
                          "peak_mb": json.loads(mem.stdout.strip().splitlines()[-1])["peak_mb"]}
        pt = rows["pt"]
        for arch in ARCHS: rows[arch]["time_vs_pt"] = rows[arch]["step_s_median"] / pt["step_s_median"]; rows[arch]["memory_vs_pt"] = rows[arch]["peak_mb"] / pt["peak_mb"]
        out["sizes"][size] = rows
        print(size, json.dumps({k: (round(v["step_s_median"], 3), round(v["peak_mb"])) for k, v in rows.items()}), flush=True)
    provenance.record("benchmarks/ablation_cost.py", out, "results/ablation_cost.json", threads=a.threads, load_average=load,
                      note="2 CPU cores shared with other jobs; round-robin timing spreads their load over all architectures")

if __name__ == "__main__":
    main()
