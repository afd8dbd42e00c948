"""The package layout stays the one described in README.md ("Architecture").

The imports of every module of ``splineimu/`` are read with ``ast`` (nothing is imported), including
the lazy ones inside functions; only imports under ``if TYPE_CHECKING:`` are left out, since they
never run. Checked: module sizes, thin command modules, library modules never importing the
command line, no import cycle, and each layer importing only the layers below it.
"""

from __future__ import annotations

import ast
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
PKG = REPO / "splineimu"

MAX_MODULE_LINES = 600
MAX_COMMAND_LINES = 200

# Layers, lowest first; a module may import its own layer and the layers before it. A module is
# placed by the first rule (a prefix of its dotted name below ``splineimu``) that matches it.
LAYERS = ("kernels", "foundation", "math", "io", "api", "cli")
LAYER_RULES = (
    ("_kernels", "kernels"),
    ("_jit", "kernels"),
    ("errors", "foundation"),
    ("validation", "foundation"),
    ("timegrid", "foundation"),
    ("io", "io"),
    ("plots", "io"),
    ("api", "api"),
    ("cli", "cli"),
    ("commands", "cli"),
    ("__main__", "cli"),
    ("", "math"),  # everything else: lie, spline, motion, scenes, imu, allan, ...
)


def module_name(path: Path) -> str:
    parts = list(path.relative_to(REPO).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def modules() -> dict[str, Path]:
    return {module_name(p): p for p in sorted(PKG.rglob("*.py")) if "__pycache__" not in p.parts}


def _is_type_checking(node: ast.If) -> bool:
    t = node.test
    return (isinstance(t, ast.Name) and t.id == "TYPE_CHECKING") or (
        isinstance(t, ast.Attribute) and t.attr == "TYPE_CHECKING")


def _import_nodes(tree: ast.AST):
    stack = [tree]
    while stack:
        node = stack.pop()
        if isinstance(node, ast.If) and _is_type_checking(node):
            stack.extend(node.orelse)
            continue
        if isinstance(node, (ast.Import, ast.ImportFrom)):
            yield node
        stack.extend(ast.iter_child_nodes(node))


def imports_of(name: str, path: Path, known: dict[str, Path]) -> set[str]:
    """Modules of splineimu that module ``name`` imports (anywhere in it), by dotted name.

    ``from pkg import x`` counts as importing ``pkg.x`` when that is a module, else ``pkg``.
    The parent packages that Python initializes on the way are not counted: they are loaded
    before any of their modules and cannot close a cycle through them.
    """
    is_pkg = path.name == "__init__.py"
    package = name if is_pkg else name.rpartition(".")[0]
    out = set()
    for node in _import_nodes(ast.parse(path.read_text(encoding="utf-8"), str(path))):
        if isinstance(node, ast.Import):
            out.update(a.name for a in node.names if a.name.split(".")[0] == "splineimu")
            continue
        if node.level:
            base = package.split(".")
            base = base[:len(base) - (node.level - 1)]
            target = ".".join(base + ([node.module] if node.module else []))
        else:
            target = node.module or ""
        if target.split(".")[0] != "splineimu":
            continue
        for alias in node.names:
            sub = f"{target}.{alias.name}"
            out.add(sub if sub in known else target)
    return {m for m in out if m in known and m != name}


def import_graph() -> dict[str, set[str]]:
    known = modules()
    return {name: imports_of(name, path, known) for name, path in known.items()}


def find_cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components with more than one module (Tarjan), each sorted."""
    index, low, on_stack, stack, out = {}, {}, set(), [], []
    counter = [0]

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on_stack.add(v)
        for w in sorted(graph.get(v, ())):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(sorted(comp))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return sorted(out)


def layer_of(name: str) -> str:
    if any(part.startswith("_kernels") for part in name.split(".")):
        return "kernels"  # splineimu/_kernels/ and a package's private kernels (camera/_kernels.py)
    rel = name.split(".", 1)[1] if "." in name else ""
    for prefix, layer in LAYER_RULES:
        if rel == prefix or rel.startswith(prefix + ".") or prefix == "":
            return layer
    raise AssertionError(name)


def is_cli(name: str) -> bool:
    return layer_of(name) == "cli"


# ---- the checker checks what it should ------------------------------------------------------

def test_cycle_finder_and_layers_on_small_cases():
    assert find_cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]
    assert find_cycles({"a": {"b"}, "b": set()}) == []
    assert layer_of("splineimu._kernels.lie") == "kernels"
    assert layer_of("splineimu.camera._kernels") == "kernels"
    assert layer_of("splineimu.io.tum") == "io"
    assert layer_of("splineimu.commands.run") == "cli"
    assert layer_of("splineimu.spline.fit") == "math"
    assert layer_of("splineimu") == "math"


def test_import_parsing_sees_lazy_relative_and_package_imports(tmp_path):
    src = tmp_path / "m.py"
    src.write_text("from typing import TYPE_CHECKING\nfrom . import lie\nfrom .io import read_tum\n"
                   "if TYPE_CHECKING:\n    from . import cli\n"
                   "def f():\n    from .commands import run\n    import splineimu.errors\n")
    known = {k: Path() for k in ("splineimu.lie", "splineimu.io", "splineimu.commands",
                                 "splineimu.commands.run", "splineimu.errors", "splineimu.cli")}
    assert imports_of("splineimu.m", src, known) == {
        "splineimu.lie", "splineimu.io", "splineimu.commands.run", "splineimu.errors"}


def test_graph_covers_the_package():
    graph = import_graph()
    assert "splineimu.cli" in graph and "splineimu.spline" in graph
    assert any(graph.values()), "no import found: the parser is broken"


# ---- the rules ------------------------------------------------------------------------------

def test_no_module_over_600_lines():
    long = {n: len(p.read_text(encoding="utf-8").splitlines()) for n, p in modules().items()}
    over = {n: k for n, k in long.items() if k > MAX_MODULE_LINES}
    assert not over, f"modules over {MAX_MODULE_LINES} lines (split by responsibility): {over}"


def test_command_modules_are_thin():
    over = {p.name: k for p in sorted((PKG / "commands").glob("*.py"))
            if (k := len(p.read_text(encoding="utf-8").splitlines())) > MAX_COMMAND_LINES}
    assert not over, f"commands over {MAX_COMMAND_LINES} lines (move the work into the library): {over}"


def test_library_never_imports_the_command_line():
    bad = {n: sorted(d for d in deps if is_cli(d)) for n, deps in import_graph().items() if not is_cli(n)}
    bad = {n: d for n, d in bad.items() if d}
    assert not bad, f"library modules importing cli/commands: {bad}"


def test_no_import_cycle():
    cycles = find_cycles(import_graph())
    assert not cycles, "import cycles (lazy imports count):\n" + "\n".join(" <-> ".join(c) for c in cycles)


def layer_violations(allow_math_io: bool) -> list[str]:
    rank = {layer: i for i, layer in enumerate(LAYERS)}
    bad = []
    for name, deps in import_graph().items():
        for d in sorted(deps):
            low, high = layer_of(name), layer_of(d)
            if rank[high] > rank[low] and not (allow_math_io and (low, high) == ("math", "io")):
                bad.append(f"{name} ({low}) imports {d} ({high})")
    return bad


def test_layers_import_only_lower_layers():
    bad = layer_violations(allow_math_io=True)
    assert not bad, "imports against the layers (README, Architecture):\n" + "\n".join(bad)


def test_math_never_imports_io():
    bad = [v for v in layer_violations(allow_math_io=False) if v.endswith("(io)") and "(math) imports" in v]
    assert not bad, "math modules importing io:\n" + "\n".join(bad)
