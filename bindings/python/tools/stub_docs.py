"""Keeps the docstrings of ``python/hystcomp/_hystcomp.pyi`` equal to the extension's own.

Editors show the stub, not the compiled module, so every class, method, property and function
in the stub carries the docstring the Rust code gives it. ``python tools/stub_docs.py`` rewrites
the stub's docstrings from the built extension (``maturin develop`` first);
``--check`` lists the differences and exits 1 (the Python tests run it).
"""

from __future__ import annotations

import ast
import inspect
import sys
from pathlib import Path

STUB = Path(__file__).resolve().parents[1] / "python" / "hystcomp" / "_hystcomp.pyi"


def runtime_doc(module, path):
    """The runtime docstring of ``module.a.b``, cleaned, or None."""
    obj = module
    for name in path:
        if isinstance(obj, type) and name in obj.__dict__:
            obj = obj.__dict__[name]
            obj = getattr(obj, "__func__", obj)  # a staticmethod's function
        else:
            obj = getattr(obj, name, None)
        if obj is None:
            return None
    doc = getattr(obj, "__doc__", None)
    if not doc or (isinstance(obj, type) and doc == type.__doc__):
        return None
    return inspect.cleandoc(doc)


def nodes(tree):
    """(path, node) of every documented-able node: classes, their functions, functions."""
    for node in tree.body:
        if isinstance(node, ast.ClassDef):
            yield (node.name,), node
            for item in node.body:
                if isinstance(item, ast.FunctionDef) and not (item.name.startswith("__") and item.name != "__init__"):
                    yield (node.name, item.name), item
        elif isinstance(node, ast.FunctionDef):
            yield (node.name,), node


def differences(module, text):
    tree = ast.parse(text)
    out = []
    for path, node in nodes(tree):
        if path[-1] == "__init__":
            continue
        want = runtime_doc(module, path)
        if want is None:
            continue
        have = ast.get_docstring(node)
        if have != want:
            out.append((path, node, want))
    return out


def rewrite(text, diffs):
    lines = text.split("\n")
    for path, node, want in sorted(diffs, key=lambda d: -d[1].lineno):
        indent = " " * (node.col_offset + 4)
        body = want
        doc_lines = [indent + '"""' + body.split("\n")[0]] + [
            (indent + line) if line else "" for line in body.split("\n")[1:]
        ]
        doc_lines[-1] += '"""'
        first = node.body[0]
        has_doc = isinstance(first, ast.Expr) and isinstance(getattr(first, "value", None), ast.Constant) and isinstance(first.value.value, str)
        if has_doc:
            start, end = first.lineno - 1, first.end_lineno
            lines[start:end] = doc_lines
        elif isinstance(first, ast.Expr) and isinstance(first.value, ast.Constant) and first.value.value is Ellipsis:
            line = lines[first.lineno - 1]
            if first.lineno == node.lineno or first.lineno == getattr(node.args, "end_lineno", node.lineno) or line.rstrip().endswith(": ..."):
                # `def f(...) -> T: ...` on one line: the docstring replaces the ellipsis.
                col = first.col_offset
                lines[first.lineno - 1] = line[:col].rstrip()
                lines[first.lineno:first.lineno] = doc_lines
            else:
                lines[first.lineno - 1 : first.end_lineno] = doc_lines
        else:
            # Insert before the first statement of the body.
            lines[first.lineno - 1 : first.lineno - 1] = doc_lines
    return "\n".join(lines)


def main(argv):
    import hystcomp._hystcomp as module

    text = STUB.read_text()
    diffs = differences(module, text)
    if "--check" in argv:
        for path, _, _ in diffs:
            print("stub docstring differs from the extension's: " + ".".join(path))
        return 1 if diffs else 0
    STUB.write_text(rewrite(text, diffs))
    left = differences(module, STUB.read_text())
    print(f"rewrote {len(diffs)} docstrings; {len(left)} still differ")
    return 1 if left else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
