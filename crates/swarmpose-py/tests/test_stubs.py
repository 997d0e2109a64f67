"""The type stubs describe the module as built: the same public names, and for each
class the same public methods and properties."""

import ast
import inspect
from pathlib import Path

import swarmpose

STUB = Path(__file__).resolve().parents[1] / "python" / "swarmpose" / "__init__.pyi"


def stub_names():
    tree = ast.parse(STUB.read_text(encoding="utf-8"))
    top, members = set(), {}
    for node in tree.body:
        if isinstance(node, (ast.FunctionDef, ast.ClassDef)):
            top.add(node.name)
        if isinstance(node, ast.ClassDef):
            members[node.name] = {n.name for n in node.body if isinstance(n, ast.FunctionDef)}
        if isinstance(node, ast.AnnAssign) and isinstance(node.target, ast.Name):
            top.add(node.target.id)
    return top, members


def public(names):
    return {n for n in names if not n.startswith("_") or n in ("__version__", "__init__", "__len__", "__getitem__")}


def test_stubs_match_the_module():
    top, members = stub_names()
    exported = set(swarmpose.__all__) | {"_register_timing"}
    assert top == exported
    for name, stubbed in members.items():
        cls = getattr(swarmpose, name)
        if not inspect.isclass(cls) or issubclass(cls, Exception):
            continue
        actual = {n for n in vars(cls) if not n.startswith("_") or n in ("__len__", "__getitem__")}
        assert public(stubbed) - {"__init__"} == actual, name
