#!/usr/bin/env python3
"""The docstrings of eopnp/__init__.pyi, generated from the runtime objects' ``__doc__``.

One source: the Rust doc comments of python/src (``///`` on the pyfunctions, pyclasses,
methods, getters and fields, and the exceptions' ``create_exception!`` texts), which become
``__doc__`` of the extension module's objects, and the docstring of eopnp/__init__.py (the
module's). The stub's docstrings are copies of them, so that ``help()`` and an IDE (which reads
the stub) show the same text.

Every class and function (``def``, including methods and properties) of the stub gets the
``__doc__`` of the object of the same name at run time (``eopnp.<name>``, or
``eopnp.<class>.<name>`` for a member); the stub's module docstring gets ``eopnp.__doc__``.
Objects without a ``__doc__``, private types of the stub alone (``_RansacInfo``), and dunder
methods (``__new__``, ``__eq__``, ...: their runtime ``__doc__`` is Python's generic one; the
class docstring documents the constructor) get none.
The stub has no other string statements (type aliases are documented by comments).

Normalisation: both sides through ``inspect.cleandoc`` (leading and common indentation
removed, trailing blank lines dropped). A generated docstring is written as a triple-quoted
string indented to its place.

Usage (with the package built and installed, from anywhere):

    python python/gen_stub_docs.py            # rewrite the stub's docstrings
    python python/gen_stub_docs.py --check    # exit 1, listing each difference, if they differ

python/tests/test_stub_docs.py runs the check, so that a docstring changed on one side only
fails the tests.
"""

from __future__ import annotations

import argparse
import ast
import inspect
import pathlib
import sys

STUB = pathlib.Path(__file__).resolve().parent / "eopnp" / "__init__.pyi"


def normalise(doc: str | None) -> str | None:
    """The docstring as compared: ``inspect.cleandoc``, None when empty."""
    if doc is None or not doc.strip():
        return None
    return inspect.cleandoc(doc)


def runtime_doc(module: object, path: tuple[str, ...]) -> str | None:
    """The normalised ``__doc__`` of ``module.<path>``; None for dunders and undocumented
    objects. A public name missing at run time raises ``LookupError`` (stubtest reports those
    too); a private one is a type of the stub alone."""
    if path and path[-1].startswith("__") and path[-1].endswith("__"):
        return None
    obj = module
    for name in path:
        try:
            obj = getattr(obj, name)
        except AttributeError:
            if name.startswith("_"):  # a type of the stub only (e.g. a TypedDict)
                return None
            raise LookupError(f"{'.'.join(path)}: in the stub, not at run time") from None
    return normalise(getattr(obj, "__doc__", None))


def literal(doc: str, indent: int) -> str:
    """``doc`` as a triple-quoted string literal whose continuation lines are indented by
    ``indent`` spaces (the first line is placed by the caller)."""
    if '"""' in doc:
        raise ValueError(f"a docstring contains triple quotes: {doc[:60]!r}")
    prefix = "r" if "\\" in doc else ""
    pad = " " * indent
    lines = doc.split("\n")
    if len(lines) == 1 and not doc.endswith('"'):
        return f'{prefix}"""{doc}"""'
    body = "\n".join((pad + ln) if ln else "" for ln in lines[1:])
    return f'{prefix}"""{lines[0]}' + ("\n" + body if body else "") + f'\n{pad}"""'


def is_docstring(stmt: ast.stmt) -> bool:
    return (
        isinstance(stmt, ast.Expr)
        and isinstance(stmt.value, ast.Constant)
        and isinstance(stmt.value.value, str)
    )


def is_ellipsis(stmt: ast.stmt) -> bool:
    return (
        isinstance(stmt, ast.Expr)
        and isinstance(stmt.value, ast.Constant)
        and stmt.value.value is Ellipsis
    )


class Stub:
    """The stub's source as lines of bytes (``ast`` column offsets are in UTF-8 bytes), and
    the edits to make, applied from the end."""

    def __init__(self, text: str) -> None:
        self.text = text
        self.lines = text.encode().splitlines(keepends=True)
        self.edits: list[tuple[int, int, int, int, bytes]] = []

    def offset(self, line: int, col: int) -> int:
        return sum(len(ln) for ln in self.lines[: line - 1]) + col

    def replace(self, start: tuple[int, int], end: tuple[int, int], text: str) -> None:
        self.edits.append((self.offset(*start), self.offset(*end), 0, 0, text.encode()))

    def result(self) -> str:
        data = b"".join(self.lines)
        for a, b, _, _, text in sorted(self.edits, key=lambda e: e[0], reverse=True):
            data = data[:a] + text + data[b:]
        return data.decode()


def plan(stub: Stub, tree: ast.Module, module: object) -> list[str]:
    """Records the edits that give every docstring of the stub its runtime text; returns the
    differences found (one line each)."""
    diffs: list[str] = []

    def visit(body: list[ast.stmt], path: tuple[str, ...], node: ast.AST | None) -> None:
        want = runtime_doc(module, path) if node is not None else normalise(module.__doc__)
        name = ".".join(path) or "the module"
        first = body[0] if body else None
        have = normalise(first.value.value) if first is not None and is_docstring(first) else None
        if have != want:
            what = "missing" if have is None else ("extra" if want is None else "differs")
            diffs.append(f"{name}: docstring {what}")
            indent = (node.col_offset + 4) if node is not None else 0
            pad = " " * indent
            if have is not None:  # replace or remove the stub's docstring
                start, end = (first.lineno, first.col_offset), (first.end_lineno, first.end_col_offset)
                if want is not None:
                    stub.replace(start, end, literal(want, indent))
                elif len(body) == 1:
                    stub.replace(start, end, "...")
                else:  # the docstring's whole lines
                    stub.replace((first.lineno, 0), (body[1].lineno, 0), "")
            elif node is None:  # a module docstring, at the top
                stub.replace((1, 0), (1, 0), literal(want, 0) + "\n\n")
            elif len(body) == 1 and is_ellipsis(first):  # `def f(...) -> T: ...`
                line = stub.lines[first.lineno - 1]
                head = line[: first.col_offset].rstrip()
                stub.replace(
                    (first.lineno, 0),
                    (first.end_lineno, first.end_col_offset),
                    head.decode() + "\n" + pad + literal(want, indent),
                )
            else:  # a class with members: before the first one
                stub.replace((first.lineno, 0), (first.lineno, 0), pad + literal(want, indent) + "\n")
        for k, stmt in enumerate(body):
            if is_docstring(stmt) and k > 0:
                diffs.append(f"{name}: a string statement that is not a docstring (line {stmt.lineno})")
            if isinstance(stmt, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
                if node is None or isinstance(node, ast.ClassDef):
                    visit(stmt.body, path + (stmt.name,), stmt)

    visit(tree.body, (), None)
    return diffs


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--check", action="store_true", help="report differences, change nothing")
    ap.add_argument("stub", nargs="?", default=str(STUB), help=f"the stub (default {STUB})")
    args = ap.parse_args()
    # The installed package, not the source tree beside this script (which has no extension
    # module): Python puts the script's directory first on sys.path.
    here = pathlib.Path(__file__).resolve().parent
    sys.path[:] = [p for p in sys.path if pathlib.Path(p or ".").resolve() != here]
    import eopnp

    path = pathlib.Path(args.stub)
    text = path.read_text()
    stub = Stub(text)
    diffs = plan(stub, ast.parse(text), eopnp)
    if args.check:
        if diffs:
            print(f"{path}: {len(diffs)} docstring(s) differ from the runtime __doc__ of eopnp "
                  f"({eopnp.__file__}):")
            for d in diffs:
                print("  " + d)
            print("Edit the Rust doc comments (python/src) or eopnp/__init__.py, rebuild, and run "
                  "`python python/gen_stub_docs.py` to regenerate the stub's docstrings.")
            return 1
        print(f"{path}: every docstring equals the runtime __doc__")
        return 0
    new = stub.result()
    if new != text:
        path.write_text(new)
    print(f"{path}: {len(diffs)} docstring(s) regenerated")
    return 0


if __name__ == "__main__":
    sys.exit(main())
