"""docs/components.md runs: every ```python block of the guide, in order, in one namespace.

The blocks carry their own assertions (analytic values, invariants), so the guide's examples
are what is tested; a failure's traceback points at the line of docs/components.md.
"""
import pathlib
import re

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]
GUIDE = ROOT / "docs" / "components.md"
FENCE = re.compile(r"^```python\n(.*?)^```$", re.S | re.M)


def python_blocks(text):
    """``(first line number, code)`` of every ```python block of a markdown ``text``."""
    return [(text.count("\n", 0, m.start(1)) + 1, m.group(1)) for m in FENCE.finditer(text)]


def test_python_blocks_are_found_with_their_line_numbers():
    text = "intro\n```python\nx = 1\n```\n```bash\nls\n```\n```python\ny = 2\nz = 3\n```\n"
    assert python_blocks(text) == [(3, "x = 1\n"), (9, "y = 2\nz = 3\n")]


def test_guide_covers_every_role_it_promises():
    text = GUIDE.read_text()
    code = "".join(c for _, c in python_blocks(text))
    for base in ("(ForceElement)", "(FlangeElement)", "(Body)", "(Joint)", "(Model)"):
        assert base in code, f"the guide has no example subclassing {base}"
    for member in ("def wrenches", "def potential", "def flange_forces", "def mass_properties", "def relative",
                   "def motion", "def constraints", "def velocity_constraints", "def outputs", "def result_notes",
                   "def measure", "def axis_world", "tree_edge = False", "external = True"):
        assert member in code, f"the guide's examples never show {member!r}"


def test_guide_examples_run():
    """Each block is compiled with its own line numbers in the markdown file, so a failing
    assertion's traceback names ``docs/components.md`` and the line."""
    blocks = python_blocks(GUIDE.read_text())
    assert len(blocks) >= 10
    namespace = {"__name__": "components_guide"}
    for line, code in blocks:
        compiled = compile("\n" * (line - 1) + code, str(GUIDE), "exec")
        try:
            exec(compiled, namespace)
        except Exception as exc:  # noqa: BLE001 - re-raised naming the block
            pytest.fail(f"docs/components.md, block at line {line}: {type(exc).__name__}: {exc}")
