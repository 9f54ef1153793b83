"""Run chapters as `nbdev_test` does (`slow` cells skipped), keeping their outputs (figures, `show_doc`) in the notebooks.
Usage: python scripts/run_book.py [--slow] nbs/00_tree.ipynb ... (`make book`), then `nbdev_clean`. `--slow` runs
the cells flagged `slow` too (05_train's pictures of the shipped model). A PNG over 50 kB is stored with 256 colours
and halved until it fits; stderr (progress bars, warnings) and JPEG twins of pictures are dropped.
"""
import base64, io, os, sys
from pathlib import Path

from execnb.nbio import read_nb, write_nb
from execnb.shell import CaptureShell
from fastcore.xtras import working_directory
from nbdev.config import get_config
from nbdev.process import NBProcessor
from PIL import Image

MAX_PNG, NOISE = 50_000, ("[Open3D", "Jupyter environment detected")


def small_png(b64: str) -> str:
    "The picture `b64` (base64 PNG) re-encoded to at most `MAX_PNG` bytes."
    data = base64.b64decode(b64); img = Image.open(io.BytesIO(data))
    while len(data) > MAX_PNG:
        img = img.convert("RGB").quantize(256) if img.mode != "P" else img.resize((img.width // 2, img.height // 2))
        buf = io.BytesIO(); img.save(buf, "PNG", optimize=True); data = buf.getvalue()
    return base64.b64encode(data).decode()


def tidy(outputs: list) -> list:
    "Outputs worth keeping: no stderr, no announcements, one small PNG per picture, no widget views."
    out = []
    for o in outputs:
        if o.get("output_type") == "stream":
            o["text"] = "".join(l for l in "".join(o["text"]).splitlines(True) if not l.startswith(NOISE))
            if o.get("name") == "stderr" or not o["text"].strip(): continue
        data = o.get("data", {})
        data.pop("application/vnd.jupyter.widget-view+json", None)
        if "image/png" in data: data.pop("image/jpeg", None); data["image/png"] = small_png("".join(data["image/png"]))
        out.append(o)
    return out


def run(fn: Path, skip=("slow",)):
    "Execute `fn` as nbdev_test does and write it back with its (tidied) outputs."
    os.environ["IN_TEST"] = "1"
    nb = NBProcessor(fn, process=True).nb   # parses the directives (`#| slow`, `#| eval: false`)
    def no_eval(cell):
        d = getattr(cell, "directives_", {}) or {}
        return cell.cell_type != "code" or d.get("eval:", [""])[0].lower() == "false" or bool(set(skip) & d.keys())
    with working_directory(fn.parent): CaptureShell(fn, mpl_format="png").run_all(nb, exc_stop=True, preproc=no_eval)
    raw, ran = read_nb(fn), {c.get("id"): c for c in nb.cells}
    for c in raw.cells:
        if c.cell_type == "code" and c.get("id") in ran: c.outputs = tidy(ran[c.id].get("outputs", []))
    write_nb(raw, fn)


if __name__ == "__main__":
    get_config(); args = sys.argv[1:]
    for a in [a for a in args if a != "--slow"]:
        run(Path(a).resolve(), () if "--slow" in args else ("slow",))
        print(f"ran {a}: {Path(a).stat().st_size / 1e3:.0f} kB")
