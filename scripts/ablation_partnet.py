"""The merging ablation of TreePartNet (paper Table 1): four networks, same data, same number of steps, one switch each.

Usage: python scripts/ablation_partnet.py [--steps 1500] [--width 32] [--work tmp/ablation-partnet]

Trains `full`, `no cosine` (Euclidean embedding distance only), `no focal` (plain binary cross-entropy) and `neither`
with scripts/train_partnet.py, all without our pair term and merged at the paper's 0.5 (resumable: re-running goes on where a variant stopped; finished variants are kept), then
writes results/partnet_ablation.json: per variant the held-out affinity and merging precision / recall / F1, RI and NMI.
"""
import argparse, json, subprocess, sys, time
from pathlib import Path
import provenance   # scripts/provenance.py, beside this script

root = Path(__file__).resolve().parent.parent
VARIANTS = {"full": [], "no cosine": ["--no-cosine"], "no focal": ["--no-focal"], "neither": ["--no-cosine", "--no-focal"]}

def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--steps", type=int, default=1500); ap.add_argument("--width", type=int, default=32)
    ap.add_argument("--batch", type=int, default=4); ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--work", default=str(root / "tmp" / "ablation-partnet"))
    a = ap.parse_args()
    work = Path(a.work); work.mkdir(parents=True, exist_ok=True)
    rows = {}
    for name, flags in VARIANTS.items():
        tag = name.replace(" ", "-")
        rec = work / f"{tag}.json"
        if not rec.exists():
            cmd = [sys.executable, str(root / "scripts" / "train_partnet.py"), "--steps", str(a.steps), "--minutes", "100000", "--width", str(a.width),
                   "--batch", str(a.batch), "--threads", str(a.threads), "--work", str(work / tag), "--out", str(work / f"{tag}.pt"),
                   "--results", str(rec), "--no-pair-term", "--fit-scans", "0", *flags]  # the paper's model, merged at 0.5
            print(f"== {name}: {' '.join(cmd[1:])}", flush=True)
            subprocess.run(cmd, check=True)
        r = json.loads(rec.read_text())
        rows[name] = dict(steps=r["steps"], minutes=r["minutes"], **r["metrics"])
    commit = provenance.commit(short=True)
    out = root / "results" / "partnet_ablation.json"
    out.write_text(json.dumps(dict(command="python scripts/ablation_partnet.py " + " ".join(sys.argv[1:]), commit=commit,
                                   time=time.strftime("%Y-%m-%d %H:%M:%S"), width=a.width, batch=a.batch, rows=rows), indent=1))
    for name, r in rows.items():
        print(f"{name:10s} affinity P {r['aff_precision']:.3f} R {r['aff_recall']:.3f} F1 {r['aff_f1']:.3f} | merged P {r['precision']:.3f} "
              f"R {r['recall']:.3f} F1 {r['f1']:.3f} | RI {r['ri']:.3f} NMI {r['nmi']:.3f}")
    print(f"wrote {out}")

if __name__ == "__main__":
    main()
