"""The package layout is the pipeline: layers import only downwards, the framework never
imports the component library, files and functions stay small enough to read.

These are structural invariants of the restructure (issue 14); each can fail when someone
adds an upward import, a library import in the framework, or grows a module past its limit.
"""
import ast
import pathlib
import subprocess
import sys

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]
SRC = ROOT / "src" / "mbcomp"

#: the pipeline, in import order; a module may import its own layer and the layers before it
LAYERS = ["errors", "geometry", "modeling", "assembly", "formulations", "solvers", "codegen", "visual", "simulation",
          "analysis", "export", "cli"]
#: the only imports against the pipeline's direction, each a public method that is a facade
#: of a later stage (imported inside the method, on call): (importing file, imported module) -> why
FACADES = {
    ("modeling/model.py", "visual.topology_drawing"): "Model.draw(path) is the model's facade of the topology drawing",
}
MAX_FILE_LINES = 650
MAX_FUNCTION_LINES = 80
WHY_LONG = "# long:"  # a function over the limit must say why it cannot be split, on a line starting so


def _modules():
    for p in sorted(SRC.rglob("*.py")):
        yield p, p.relative_to(SRC).with_suffix("").parts


def _layer(parts):
    return parts[0] if parts[0] in LAYERS else None


def _imports(path, parts, top_level_only=False):
    """Every ``mbcomp`` module a file imports (top level and inside functions, or top level
    only), as ``(part tuple, line)``."""
    tree = ast.parse(path.read_text())
    pkg = parts[:-1]
    for node in (tree.body if top_level_only else ast.walk(tree)):
        if isinstance(node, ast.ImportFrom):
            if node.level:
                base = list(pkg[: len(pkg) - node.level + 1])
                mod = base + (node.module.split(".") if node.module else [])
                if node.module is None:  # from . import x
                    for a in node.names:
                        yield tuple(mod + [a.name]), node.lineno
                else:
                    yield tuple(mod), node.lineno
            elif node.module and node.module.split(".")[0] == "mbcomp":
                yield tuple(node.module.split(".")[1:]), node.lineno
        elif isinstance(node, ast.Import):
            for a in node.names:
                if a.name.split(".")[0] == "mbcomp":
                    yield tuple(a.name.split(".")[1:]), node.lineno


def test_layers_import_only_downwards():
    bad = []
    for path, parts in _modules():
        me = _layer(parts)
        if me is None:  # mbcomp/__init__.py and the alias table sit above the pipeline
            continue
        for target, line in _imports(path, parts):
            if not target:
                continue
            if target[0] == "library":
                bad.append(f"{path.relative_to(ROOT)}:{line} imports the component library")
                continue
            other = _layer(target)
            if other is None:
                bad.append(f"{path.relative_to(ROOT)}:{line} imports mbcomp.{'.'.join(target)} (not a pipeline layer)")
            elif LAYERS.index(other) > LAYERS.index(me) and (str(path.relative_to(SRC)), ".".join(target)) not in FACADES:
                bad.append(f"{path.relative_to(ROOT)}:{line} ({me}) imports upwards from {other}")
    assert not bad, "\n".join(bad)


def test_importing_the_framework_imports_no_library_module():
    mods = [".".join(("mbcomp",) + p).removesuffix(".__init__") for _, p in _modules()
            if p[-1] != "__main__"]
    code = ("import importlib, sys\n"
            f"for m in {mods!r}: importlib.import_module(m)\n"
            "bad = sorted(m for m in sys.modules if m.startswith('mbcomp.library'))\n"
            "print(','.join(bad))\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.strip()
    assert out == "", f"importing the framework imported {out}"


def test_no_file_over_the_limit():
    long = [f"{p.relative_to(ROOT)}: {n} lines" for p, _ in _modules()
            if (n := len(p.read_text().splitlines())) > MAX_FILE_LINES]
    assert not long, f"files over {MAX_FILE_LINES} lines:\n" + "\n".join(long)


def _code_lines(src_lines, node):
    """Lines of code of a function body: no blank lines, comments or docstring."""
    body = node.body
    start = body[0].lineno
    if isinstance(body[0], ast.Expr) and isinstance(getattr(body[0], "value", None), ast.Constant) \
            and isinstance(body[0].value.value, str):
        start = body[0].end_lineno + 1
    lines = src_lines[start - 1: node.end_lineno]
    return sum(1 for s in lines if s.strip() and not s.strip().startswith("#"))


def test_no_function_over_the_limit_without_saying_why():
    long = []
    for path, _ in _modules():
        text = path.read_text()
        src_lines = text.splitlines()
        for node in ast.walk(ast.parse(text)):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                n = _code_lines(src_lines, node)
                own = src_lines[node.lineno - 1: node.end_lineno]
                if n > MAX_FUNCTION_LINES and not any(s.strip().startswith(WHY_LONG) for s in own):
                    long.append(f"{path.relative_to(ROOT)}:{node.lineno} {node.name}: {n} lines of code")
    assert not long, f"functions over {MAX_FUNCTION_LINES} lines of code with no '{WHY_LONG}' comment:\n" + "\n".join(long)


@pytest.mark.parametrize("pattern", ["formulation ==", "method in METHODS", "_ONE_STEP", "isinstance(", "hasattr("])
def test_driver_asks_no_names_or_types(pattern):
    driver = SRC / "simulation" / "driver.py"
    hits = [f"{i}: {s.strip()}" for i, s in enumerate(driver.read_text().splitlines(), 1)
            if pattern in s and not s.strip().startswith("#")]
    assert not hits, f"the driver branches on {pattern!r}:\n" + "\n".join(hits)


def test_old_module_paths_are_the_new_modules():
    import importlib

    from mbcomp._aliases import OLD_PATHS

    for old, new in OLD_PATHS.items():
        assert importlib.import_module(f"mbcomp.{old}") is importlib.import_module(f"mbcomp.{new}"), old


def test_no_import_cycles():
    """Module-level imports between mbcomp modules form no cycle (imports inside functions
    are allowed to break one, and are listed by the layer test above)."""
    import networkx as nx

    g = nx.DiGraph()
    for path, parts in _modules():
        me = ".".join(parts).removesuffix(".__init__")
        for t, _ in _imports(path, parts, top_level_only=True):
            if SRC.joinpath(*t).with_suffix(".py").exists() or (SRC.joinpath(*t) / "__init__.py").exists():
                g.add_edge(me, ".".join(t))
    cycles = list(nx.simple_cycles(g))
    assert not cycles, "import cycles: " + "; ".join(" -> ".join(c) for c in cycles[:5])


def test_every_path_in_the_architecture_exists():
    import re

    text = (ROOT / "docs" / "architecture.md").read_text()
    paths = set(re.findall(r"(?<![\w./-])((?:[A-Za-z_][\w]*/)+(?:[\w-]+\.(?:py|json|md))?)(?![\w/])", text))
    missing = [p for p in sorted(paths)
               if not any((base / p).exists() for base in (ROOT, SRC, ROOT / "src"))]
    assert paths and not missing, f"docs/architecture.md names paths that do not exist: {missing}"
