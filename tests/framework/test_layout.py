"""The package layout is the pipeline: layers import only downwards, the framework never
imports the component library, no import cycles (imports inside functions count), no module
uses another module's private names or another object's private attributes.

These are structural invariants of the restructure (issues 14 and 30); each can fail when
someone adds an upward import, a library import in the framework, a cycle hidden in a
function, or a reach into another module's ``_private`` names.

File and function length are a hint, not a design rule: the limits below stay as an alarm
that a module or function may hold more than one responsibility, but code is split by
responsibility (what it computes, for whom), never moved just to get under a count. A
function over the limit says why on a ``# long:`` line.
"""
import ast
import pathlib
import subprocess
import sys

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]
SRC = ROOT / "src" / "mbcomp"

#: the pipeline, in import order; a module may import its own layer and the layers before it
LAYERS = ["errors", "geometry", "modeling", "assembly", "formulations", "solvers", "codegen", "visual", "hybrid", "simulation",
          "analysis", "export", "io", "cli"]
#: layers that write models of library components, as a user's model file does (importing the
#: library inside their functions, on call: importing them imports no library module)
MODEL_AUTHORS = {"io": "the importers turn URDF/MJCF elements into library components"}
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


def _imports(path, parts):
    """Every ``mbcomp`` import of a file, at the top level and inside functions alike (an
    import in a function runs as surely as one at the top, only later), as ``(target parts,
    line, names)``: ``names`` are what a ``from ... import`` takes from the target (``[]``
    for ``import mbcomp.x`` and ``from . import x``, whose target is the module ``x``)."""
    tree = ast.parse(path.read_text())
    pkg = parts[:-1]
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom):
            if node.level:
                base = list(pkg[: len(pkg) - node.level + 1])
                mod = base + (node.module.split(".") if node.module else [])
                if node.module is None:  # from . import x
                    for a in node.names:
                        yield tuple(mod + [a.name]), node.lineno, []
                else:
                    yield tuple(mod), node.lineno, [a.name for a in node.names]
            elif node.module and node.module.split(".")[0] == "mbcomp":
                yield tuple(node.module.split(".")[1:]), node.lineno, [a.name for a in node.names]
        elif isinstance(node, ast.Import):
            for a in node.names:
                if a.name.split(".")[0] == "mbcomp":
                    yield tuple(a.name.split(".")[1:]), node.lineno, []


def _is_module(target):
    """Whether the part tuple ``target`` names an mbcomp module or package."""
    return bool(target) and (SRC.joinpath(*target).with_suffix(".py").exists()
                             or (SRC.joinpath(*target) / "__init__.py").exists())


def _name(parts):
    return ".".join(parts).removesuffix(".__init__") or "mbcomp"


def _private(name):
    return name.startswith("_") and not (name.startswith("__") and name.endswith("__"))


def test_layers_import_only_downwards():
    bad = []
    for path, parts in _modules():
        me = _layer(parts)
        if me is None:  # mbcomp/__init__.py and the alias table sit above the pipeline
            continue
        for target, line, _ in _imports(path, parts):
            if not target:
                continue
            if target[0] == "library" and me not in MODEL_AUTHORS:
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


def _import_graph():
    """The module import graph: ``{(importer, imported): [file:line, ...]}`` over every
    import, top level or inside a function (``from pkg import sub`` imports ``pkg.sub``)."""
    edges = {}
    for path, parts in _modules():
        me = _name(parts)
        for t, line, names in _imports(path, parts):
            for target in [t] + [t + (n,) for n in names]:
                if _is_module(target) and _name(target) != me:
                    edges.setdefault((me, _name(target)), []).append(f"{path.relative_to(ROOT)}:{line}")
    return edges


def test_no_import_cycles():
    """No set of mbcomp modules imports each other in a circle, counting the imports inside
    functions: a function-local import hides a cycle from Python's loader, not from the
    design (the two modules still cannot be understood, tested or changed one without the
    other). Every strongly connected component of the import graph is reported, with the
    imports that close it."""
    import networkx as nx

    edges = _import_graph()
    g = nx.DiGraph(list(edges))
    sccs = sorted(sorted(c) for c in nx.strongly_connected_components(g) if len(c) > 1)
    report = []
    for c in sccs:
        inside = [f"    {a} -> {b} ({', '.join(edges[a, b])})" for a, b in sorted(g.subgraph(c).edges)]
        report.append(f"{{{', '.join(c)}}}:\n" + "\n".join(inside))
    assert not sccs, f"{len(sccs)} import cycles (strongly connected components):\n" + "\n".join(report)


def test_no_module_imports_another_modules_private_names():
    """No module imports another module's private names: a name with one leading underscore
    (``_x``, dunders aside) belongs to the module that defines it, which may change it
    without looking elsewhere. What another module needs is public (no underscore, in
    ``__all__`` where the module has one) in the module whose responsibility it is.

    The precise rule: ``from m import _x`` is refused whenever ``_x`` is a name defined in
    ``m``; a private *module* ``p._m`` (a file whose name starts with ``_``) is private to its
    package ``p``: ``p/__init__.py`` and the modules directly in ``p`` may import it
    (``from . import _aliases`` in ``mbcomp/__init__.py``), no module elsewhere may."""
    bad = []
    for path, parts in _modules():
        where = f"{path.relative_to(ROOT)}"
        pkg = parts[:-1]
        for t, line, names in _imports(path, parts):
            for k, part in enumerate(t):
                if _private(part) and pkg != t[:k]:
                    bad.append(f"{where}:{line} imports the private module mbcomp.{'.'.join(t[:k + 1])}")
                    break
            for n in names:
                if not _private(n):
                    continue
                if _is_module(t + (n,)):
                    if pkg != t:
                        bad.append(f"{where}:{line} imports the private module mbcomp.{_name(t + (n,))}")
                else:
                    bad.append(f"{where}:{line} imports {n} from mbcomp.{_name(t)}")
    assert not bad, f"{len(bad)} imports of another module's private names:\n" + "\n".join(bad)


class _PrivateReads(ast.NodeVisitor):
    """Reads of private attributes through anything but the method's own receiver.

    The receiver is the first parameter of a function defined directly in a class body
    (``self``, ``cls``, or any other name: ``def __lt__(a, b)``), except for static methods,
    and ``super()``; functions nested in a method see their method's receiver. Attribute
    access (``obj._x``), ``getattr``/``hasattr``/``setattr``/``delattr`` with a literal
    ``"_x"`` and ``obj.__dict__`` lookups of a literal ``"_x"`` all count."""

    ACCESSORS = ("getattr", "hasattr", "setattr", "delattr")

    def __init__(self, where):
        self.where, self.receivers, self.found = where, [frozenset()], []

    def visit_ClassDef(self, node):
        for item in node.body:
            if isinstance(item, (ast.FunctionDef, ast.AsyncFunctionDef)):
                self._function(item, method=True)
            else:
                self.visit(item)

    def visit_FunctionDef(self, node):
        self._function(node, method=False)

    visit_AsyncFunctionDef = visit_FunctionDef

    def _function(self, node, method):
        static = any(isinstance(d, ast.Name) and d.id == "staticmethod" for d in node.decorator_list)
        own = self.receivers[-1]
        if method:
            first = (node.args.posonlyargs + node.args.args)[:1]
            own = frozenset(a.arg for a in first) if first and not static else frozenset()
        self.receivers.append(own)
        self.generic_visit(node)
        self.receivers.pop()

    def _own(self, value):
        if isinstance(value, ast.Name):
            return value.id in self.receivers[-1]
        return isinstance(value, ast.Call) and isinstance(value.func, ast.Name) and value.func.id == "super"

    def _report(self, node, what):
        self.found.append(f"{self.where}:{node.lineno} {what}")

    def visit_Attribute(self, node):
        if _private(node.attr) and not self._own(node.value):
            self._report(node, f"{ast.unparse(node.value)}.{node.attr}")
        self.generic_visit(node)

    def visit_Call(self, node):
        f, args = node.func, node.args
        key = None
        if isinstance(f, ast.Name) and f.id in self.ACCESSORS and len(args) >= 2:
            obj, key = args[0], args[1]
        elif isinstance(f, ast.Attribute) and f.attr in ("get", "pop", "setdefault") and args \
                and isinstance(f.value, ast.Attribute) and f.value.attr == "__dict__":
            obj, key = f.value.value, args[0]
        if isinstance(key, ast.Constant) and isinstance(key.value, str) and _private(key.value) \
                and not self._own(obj):
            self._report(node, ast.unparse(node)[:80])
        self.generic_visit(node)

    def visit_Subscript(self, node):
        v, key = node.value, node.slice
        if isinstance(v, ast.Attribute) and v.attr == "__dict__" and isinstance(key, ast.Constant) \
                and isinstance(key.value, str) and _private(key.value) and not self._own(v.value):
            self._report(node, ast.unparse(node)[:80])
        self.generic_visit(node)


def test_no_module_reads_another_objects_private_attributes():
    """No code reads or writes a private attribute (``obj._x``) of any object but its own
    receiver (``self``, ``cls``, ``super()``; see :class:`_PrivateReads`): what another stage
    needs from an object is a public method or attribute of that object, so the object can
    change its insides without breaking its users (e.g. ``MultibodySystem._edge`` is read
    through a public accessor outside ``assembly/system.py``). There is no exception list:
    a module that needs another instance's insides of its own class asks it through a
    public method as everyone else does."""
    bad = []
    for path, _ in _modules():
        v = _PrivateReads(str(path.relative_to(ROOT)))
        v.visit(ast.parse(path.read_text()))
        bad += v.found
    assert not bad, f"{len(bad)} reads of another object's private attributes:\n" + "\n".join(bad)


def test_every_path_in_the_architecture_exists():
    import re

    text = (ROOT / "docs" / "architecture.md").read_text()
    paths = set(re.findall(r"(?<![\w./-])((?:[A-Za-z_][\w]*/)+(?:[\w-]+\.(?:py|json|md))?)(?![\w/])", text))
    missing = [p for p in sorted(paths)
               if not any((base / p).exists() for base in (ROOT, SRC, ROOT / "src"))]
    assert paths and not missing, f"docs/architecture.md names paths that do not exist: {missing}"
