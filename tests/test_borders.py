"The modules' borders: no import circle among treebook's modules, at any level of a module (inside functions too)."
import ast
from pathlib import Path

PKG = Path(__file__).resolve().parent.parent / "treebook"


def imports(path: Path) -> set:
    "The treebook modules that `path` imports: `from .x`, `from . import x`, `from treebook.x`, `import treebook.x`."
    found = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.ImportFrom):
            if node.level == 1 and node.module: found.add(node.module.split(".")[0])
            elif node.level == 1: found.update(a.name for a in node.names)
            elif node.level == 0 and node.module and node.module.split(".")[0] == "treebook":
                parts = node.module.split(".")
                if len(parts) > 1: found.add(parts[1])
                else: found.update(a.name for a in node.names)
        elif isinstance(node, ast.Import):
            found.update(a.name.split(".")[1] for a in node.names if a.name.startswith("treebook."))
    return found


def graph() -> dict:
    "Each module of treebook/ and the treebook modules it imports (files being written, named `.x`, left out)."
    files = [p for p in PKG.glob("*.py") if not p.name.startswith(".")]
    mods = {p.stem for p in files}
    return {p.stem: sorted(imports(p) & mods - {p.stem}) for p in files}


def cycle(g: dict):
    "One import circle of `g` as a list of modules (the first again at the end), or None."
    state, stack = {}, []
    def visit(m):
        state[m] = "open"; stack.append(m)
        for n in g.get(m, []):
            if state.get(n) == "open": return stack[stack.index(n):] + [n]
            if n not in state and (c := visit(n)): return c
        state[m] = "done"; stack.pop()
    for m in sorted(g):
        if m not in state and (c := visit(m)): return c


def test_finds_imports(tmp_path):
    p = tmp_path / "m.py"
    p.write_text("from .tree import Tree\nfrom . import mesh\nimport treebook.render\n"
                 "def f():\n    from treebook.scan import scan\n    from treebook import botany\n")
    assert imports(p) == {"tree", "mesh", "render", "scan", "botany"}


def test_finds_a_cycle():
    assert cycle({"a": ["b"], "b": ["c"], "c": ["a"]}) == ["a", "b", "c", "a"]
    assert cycle({"a": ["b", "c"], "b": ["c"], "c": []}) is None


def test_no_import_circle():
    g = graph()
    assert "tree" in g and g["tree"] == []
    assert cycle(g) is None, " -> ".join(cycle(g))
