"""The book's shape (issue 27's targets): `python tests/test_book.py [nbs/XX.ipynb ...]` prints the statistics.

Over the exported cells: median length in lines (directives not counted), share of lines over 120 characters, cells
of 40 lines or more; public functions and classes (and `@patch` methods) with neither `show_doc` nor an example
cell that uses them; markdown cells that name a session, an issue or a commit of this repository.
"""
import ast, json, re, statistics, subprocess, sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
NBS = sorted((ROOT / "nbs").glob("*.ipynb"))
DIRECTIVE, EXPORT = re.compile(r"^\s*#\|"), re.compile(r"^\s*#\|\s*export")
LAB = re.compile(r"\b(sessions?|issues?)\b|\bissue\s*#?\d+|(?<!\w)#\d+\b", re.I)
HEX = re.compile(r"(?<![\w/.])[0-9a-f]{7,40}(?![\w/])")
# Chapters brought to the targets: a change that breaks them fails the test below (the median over all of them).
DONE = ["00_tree", "01_mesh", "01a_render", "02_botany", "02a_scan", "02b_datasets", "03_tokens", "04_hourglass",
        "04a_sampling", "05_train", "05a_species_runs", "06_metrics", "07_ordering_ablation", "08_wavelet_grammar",
        "08a_lsystem", "08b_pointio", "09a_partnet", "09a1_partnet_runs", "09b_reconstruct",
        "10_growth_and_conditioning", "10a_condition", "10b_widgets", "11_cli", "12_demos", "index"]


def commits(words):
    "The words that name a commit of this repository."
    words = sorted({w for w in words if re.search(r"[a-f]", w) and re.search(r"\d", w)})
    if not words: return set()
    out = subprocess.run(["git", "cat-file", "--batch-check"], input="".join(f"{w}^{{commit}}\n" for w in words),
                         cwd=ROOT, capture_output=True, text=True).stdout.splitlines()
    return {w for w, line in zip(words, out) if not line.endswith("missing")}


def public(src):
    "Public top-level functions and classes of an exported cell; `@patch` methods as `Class.name`."
    try: tree = ast.parse("\n".join(l for l in src.splitlines() if not l.lstrip().startswith(("%", "!"))))
    except SyntaxError: return []
    out = []
    for node in tree.body:
        if not isinstance(node, (ast.FunctionDef, ast.ClassDef)) or node.name.startswith("_"): continue
        patched = [d for d in node.decorator_list if "patch" in ast.unparse(d)]
        if patched and node.args.args and node.args.args[0].annotation is not None:
            out.append(f"{ast.unparse(node.args.args[0].annotation).strip(chr(39) + chr(34))}.{node.name}")
        else: out.append(node.name)
    return out


def stats(paths=NBS):
    lengths, long_lines, big, undocumented, lab = [], 0, [], [], []
    for p in paths:
        cells = json.loads(Path(p).read_text())["cells"]
        src = ["".join(c["source"]) for c in cells]
        rest = "\n".join(s for c, s in zip(cells, src) if c["cell_type"] == "code" and not EXPORT.search(s))
        for c, s in zip(cells, src):
            if c["cell_type"] == "markdown":
                hits = [m.group(0) for m in LAB.finditer(s)] + sorted(commits(HEX.findall(s)))
                if hits: lab.append(f"{Path(p).name}: {', '.join(hits)}")
            if c["cell_type"] != "code" or not EXPORT.search(s): continue
            lines = [l for l in s.splitlines() if not DIRECTIVE.match(l)]
            lengths.append(len(lines)); long_lines += sum(len(l) > 120 for l in lines)
            if len(lines) >= 40: big.append(f"{Path(p).name}: {len(lines)} lines ({', '.join(public(s)) or '-'})")
            for name in public(s):
                shown = re.search(rf"show_doc\(\s*{re.escape(name)}\b", rest)
                used = re.search(rf"(?<!\w){re.escape(name.split('.')[-1])}\b", rest.replace("show_doc(", ""))
                if not (shown or used): undocumented.append(f"{Path(p).name}: {name}")
    n = max(sum(lengths), 1)
    return dict(cells=len(lengths), median=statistics.median(lengths) if lengths else 0, long_share=long_lines / n,
                big=big, undocumented=undocumented, lab=lab)


def test_done_chapters():
    paths = [ROOT / "nbs" / f"{p}.ipynb" for p in DONE]
    for p in paths:
        s = stats([p])
        assert s["long_share"] <= 0.01, (p.name, s["long_share"])
        assert not s["undocumented"] and not s["lab"], (s["undocumented"], s["lab"])
    assert stats(paths)["median"] <= 12


if __name__ == "__main__":
    s = stats([Path(a) for a in sys.argv[1:]] or NBS)
    print(f"exported cells {s['cells']}, median {s['median']} lines, {100 * s['long_share']:.2f} % of lines over 120")
    for key in "big", "undocumented", "lab": print(f"{key} ({len(s[key])}):", *s[key], sep="\n  ")
