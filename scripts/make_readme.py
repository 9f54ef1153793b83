"""Build README.md from nbs/index.ipynb: execute it, drop `#| hide` cells and directive lines, write markdown.

Quarto (which nbdev_readme needs) is not available here, so nbconvert does the job. Pictures go to images/readme/.
Usage: python scripts/make_readme.py
"""
import re
import shutil
from pathlib import Path

import nbformat
from nbconvert import MarkdownExporter
from nbconvert.preprocessors import ExecutePreprocessor

root = Path(__file__).resolve().parent.parent
nb = nbformat.read(root / "nbs" / "index.ipynb", as_version=4)
ExecutePreprocessor(timeout=900, kernel_name="python3").preprocess(nb, {"metadata": {"path": str(root / "nbs")}})

directive = re.compile(r"^\s*#\|\s*(\S+)(.*)$")
cells = []
for cell in nb.cells:
    lines = cell.source.splitlines()
    flags = {m.group(1).rstrip(":"): m.group(2).strip() for m in map(directive.match, lines) if m}
    if "hide" in flags: continue
    if cell.cell_type == "code":
        cell.source = "\n".join(l for l in lines if not directive.match(l)).strip()
        cell.outputs = [o for o in cell.outputs if o.get("output_type") != "stream" or o.get("name") != "stderr"]
        for o in cell.outputs:  # open3d announces itself when imported in Jupyter: not part of the page
            if o.get("output_type") == "stream":
                o["text"] = "".join(l for l in o["text"].splitlines(True) if not l.startswith(("[Open3D", "Jupyter environment detected")))
        cell.outputs = [o for o in cell.outputs if o.get("output_type") != "stream" or o["text"].strip()]
        for o in cell.outputs:  # one picture per output: keep the PNG
            if "image/png" in o.get("data", {}): o["data"].pop("image/jpeg", None)
        if flags.get("echo") == "false": cell.source = ""
    cells.append(cell)
nb.cells = cells

body, res = MarkdownExporter().from_notebook_node(nb)
img_dir = root / "images" / "readme"
shutil.rmtree(img_dir, ignore_errors=True)
img_dir.mkdir(parents=True)
for name, data in res.get("outputs", {}).items():
    (img_dir / name).write_bytes(data)
    body = body.replace(f"]({name})", f"](images/readme/{name})")
body = re.sub(r"```python\n\s*```\n", "", body)  # empty source of echo: false cells
body = re.sub(r"\n{3,}", "\n\n", body)
(root / "README.md").write_text("<!-- generated from nbs/index.ipynb by `make readme`: edit the notebook, not this file -->\n\n" + body.strip() + "\n")
print(f"wrote README.md and {len(res.get('outputs', {}))} picture(s) in images/readme/")
