"""The digest of the code a run executes: its roots and everything they reach, by name.

A run is computed by a few roots (its run loop, its learner, representation and strategy, the
world), chosen by its config. From each root the digest follows the names the code uses: a
function or class of this project (or of the plugin that holds a root) that a reached function
names is reached too; a method is reached when some reached code names it as an attribute
(``x.report(...)`` reaches every reached class's ``report``), dunders always; a module-level
value a reached function names is part of the digest by its value (one its module names in
``__process_state__``, state a process gathers as it goes, by its type alone). Third-party
code (numpy, torch, pymunk) is not followed: another version of it is not seen.

What a unit contributes is its qualified name and its syntax tree without docstrings, never
the file it lives in, so moving or renaming a file changes no digest; an unused class, function,
method or constant added anywhere changes none either; a change inside reached code changes
the digest of exactly the runs that reach it.
"""

from __future__ import annotations

import ast
import functools
import hashlib
import importlib
import inspect
import sys
import textwrap
import types
from collections.abc import Iterable
from typing import Any

PROJECT = "mediated_transfer"
"""Top-level package of the project's own code: always followed."""
_PROVENANCE = f"{PROJECT}.provenance"


def closure_digest(roots: Iterable[Any]) -> str:
    """16 hex digits over the units reached from ``roots`` (functions, classes, methods)."""
    return Closure(roots).digest()


class Closure:
    """The units reached from some roots; ``units`` maps a unit's key to its text."""

    def __init__(self, roots: Iterable[Any]):
        roots = list(roots)
        # A classmethod builds its class (``cls(...)``): the class is reached too.
        roots += [r.__self__ for r in roots if isinstance(r, types.MethodType) and isinstance(r.__self__, type)]
        roots = [_underlying(root) for root in roots]
        self.packages = {PROJECT} | {_top(root) for root in roots if _top(root)}
        self.units: dict[tuple[str, str], str] = {}
        self._seen: set[int] = set()
        self._attributes: set[str] = set()
        self._classes: list[tuple[type, dict[str, ast.AST]]] = []
        self._methods_done: set[tuple[int, str]] = set()
        pending = list(roots)
        while pending:
            while pending:
                self._add(pending.pop(), pending)
            # Methods of reached classes that reached code names (a fixpoint: a method reached
            # now may name further attributes).
            for cls, methods in self._classes:
                for name, node in methods.items():
                    if (id(cls), name) in self._methods_done:
                        continue
                    if name in self._attributes or (name.startswith("__") and name.endswith("__")):
                        self._methods_done.add((id(cls), name))
                        self._add_tree(f"{cls.__qualname__}.{name}", node, _globals_of(cls), pending)

    def digest(self) -> str:
        h = hashlib.sha256()
        for key in sorted(self.units):
            h.update(repr(key).encode())
            h.update(self.units[key].encode())
        return h.hexdigest()[:16]

    # --- reaching ---------------------------------------------------------------------------

    def _ours(self, obj: Any) -> bool:
        # Recording provenance is not computing: this package stays out of every digest.
        return _top(obj) in self.packages and not getattr(obj, "__module__", "").startswith(_PROVENANCE)

    def _add(self, obj: Any, pending: list) -> None:
        obj = _underlying(obj)
        if id(obj) in self._seen or not self._ours(obj):
            return
        self._seen.add(id(obj))
        if isinstance(obj, type):
            self._add_class(obj, pending)
        elif isinstance(obj, types.FunctionType):
            tree = _tree(obj)
            if tree is None:
                self.units[(obj.__qualname__, "code")] = _code_text(obj)
                return
            self._add_tree(obj.__qualname__, tree, obj.__globals__, pending)

    def _add_class(self, cls: type, pending: list) -> None:
        parts = _class_parts(cls)
        if parts is None:
            self.units[(cls.__qualname__, "class")] = cls.__qualname__
            return
        tree, methods = parts
        self._add_tree(cls.__qualname__, tree, _globals_of(cls), pending, kind="class")
        for base in cls.__bases__:
            pending.append(base)
        self._classes.append((cls, methods))

    def _add_tree(self, name: str, tree: ast.AST, namespace: dict, pending: list, kind: str = "def") -> None:
        _strip_docstrings(tree)
        self.units[(name, kind)] = _dump(tree)
        namespace = {**namespace, **self._local_imports(tree, namespace)}
        for value_name, value in self._references(tree, namespace):
            if isinstance(value, (type, types.FunctionType)) or _underlying(value) is not value:
                pending.append(value)
            elif not isinstance(value, types.ModuleType):
                for inner in _callables_in(value):
                    pending.append(inner)
                if _is_process_state(value_name, namespace):
                    value = type(value)()
                self.units[(f"{name}:{value_name}", "value")] = _stable_repr(value)

    def _local_imports(self, tree: ast.AST, namespace: dict) -> dict[str, Any]:
        """Names imported inside functions (``from .dqn_kernels import FastUpdate``): followed
        like globals, since the code runs them."""
        found: dict[str, Any] = {}
        package = namespace.get("__package__") or ""
        for node in ast.walk(tree):
            if isinstance(node, ast.ImportFrom):
                base = ("." * node.level + (node.module or "")) if node.level else (node.module or "")
                if not node.level and base.split(".")[0] not in self.packages:
                    continue  # third-party code is never followed: not imported either (sklearn: ~1 s)
                try:
                    module = importlib.import_module(base, package) if node.level else importlib.import_module(base)
                except ImportError:
                    continue
                if module.__name__.split(".")[0] not in self.packages:
                    continue
                for alias in node.names:
                    value = getattr(module, alias.name, None)
                    if value is None:
                        try:
                            value = importlib.import_module(f"{module.__name__}.{alias.name}")
                        except ImportError:
                            continue
                    found[alias.asname or alias.name] = value
            elif isinstance(node, ast.Import):
                for alias in node.names:
                    if alias.name.split(".")[0] in self.packages:
                        try:
                            module = importlib.import_module(alias.name)
                        except ImportError:
                            continue
                        found[alias.asname or alias.name.split(".")[0]] = (
                            module if alias.asname else sys.modules[alias.name.split(".")[0]])
        return found

    def _references(self, tree: ast.AST, namespace: dict):
        """(name, object) of every global name and module attribute ``tree`` uses, outside
        annotations; attribute names go to ``self._attributes``."""
        annotations = {id(n) for n in _annotation_nodes(tree)}
        for node in ast.walk(tree):
            if id(node) in annotations:
                continue
            if isinstance(node, ast.Attribute):
                self._attributes.add(node.attr)
                chain = _attribute_chain(node)
                if chain and chain[0] in namespace:
                    value = namespace[chain[0]]
                    for part in chain[1:]:
                        if not isinstance(value, types.ModuleType) or not hasattr(value, part):
                            break
                        value = getattr(value, part)
                        if isinstance(value, types.ModuleType):
                            continue
                        if self._ours(value) or _module_is_ours(namespace[chain[0]], self.packages):
                            yield ".".join(chain[:2]), value
                        break
            elif isinstance(node, ast.Name) and isinstance(node.ctx, ast.Load) and node.id in namespace:
                value = namespace[node.id]
                if isinstance(value, types.ModuleType):
                    continue
                if isinstance(value, (type, types.FunctionType)) or _underlying(value) is not value:
                    if self._ours(value):
                        yield node.id, value
                elif namespace.get("__name__", "").split(".")[0] in self.packages:
                    yield node.id, value


# --- helpers ------------------------------------------------------------------------------------


def _underlying(obj: Any) -> Any:
    """The Python function or class behind a method, a decorator or a numba dispatcher."""
    for _ in range(8):
        if isinstance(obj, (classmethod, staticmethod)):
            obj = obj.__func__
        elif isinstance(obj, types.MethodType):
            obj = obj.__func__
        elif hasattr(obj, "py_func") and callable(obj.py_func):  # numba's dispatchers
            obj = obj.py_func
        elif isinstance(obj, property) and obj.fget is not None:
            obj = obj.fget
        elif hasattr(obj, "__wrapped__") and not isinstance(obj, type):
            obj = obj.__wrapped__
        else:
            return obj
    return obj


def _top(obj: Any) -> str:
    module = getattr(obj, "__module__", None)
    if not isinstance(module, str):
        return ""
    if module == "__main__":
        return "__main__"
    return module.split(".")[0]


def _is_process_state(value_name: str, namespace: dict) -> bool:
    """Whether a module-level value is named in its module's ``__process_state__``: what this
    process has done so far (the folders the last composed config was searched in), not code.
    It is digested as its type's empty value, so a run's digest does not depend on what ran
    before it in the same process (a sweep's worker, a test suite)."""
    owner, _, attribute = value_name.rpartition(".")  # "module.value" or "value"
    state = getattr(namespace.get(owner), "__process_state__", ()) if owner else namespace.get("__process_state__", ())
    return attribute in state


def _module_is_ours(module: Any, packages: set[str]) -> bool:
    return isinstance(module, types.ModuleType) and module.__name__.split(".")[0] in packages


def _globals_of(cls: type) -> dict:
    module = sys.modules.get(cls.__module__)
    return vars(module) if module is not None else {}


@functools.lru_cache(maxsize=4096)
def _tree(obj: Any) -> ast.AST | None:
    """``obj``'s syntax tree, read and parsed once per process (every run kind's closure reaches
    the same loop, world and learners). Shared: whoever changes it must change it the same way
    every time (docstrings stripped, a class's methods split off by _class_parts)."""
    try:
        source = textwrap.dedent(inspect.getsource(obj))
    except (OSError, TypeError):
        return None
    module = ast.parse(source)
    return module.body[0] if module.body else None


@functools.lru_cache(maxsize=1024)
def _class_parts(cls: type) -> tuple[ast.AST, dict[str, ast.AST]] | None:
    """A class's tree without its methods, and its methods by name."""
    tree = _tree(cls)
    if tree is None:
        return None
    methods = {n.name: n for n in tree.body if isinstance(n, (ast.FunctionDef, ast.AsyncFunctionDef))}
    tree.body = [n for n in tree.body if not isinstance(n, (ast.FunctionDef, ast.AsyncFunctionDef))]
    tree.body = tree.body or [ast.Pass()]
    return tree, methods


_NEWER_FIELDS = frozenset({"type_params", "default_value"})
"""Fields later Pythons added to the syntax tree (3.12: type parameters; 3.13: their defaults):
left out while empty, so the same code has the same digest on 3.11, 3.12 and 3.13."""


def _dump(node: Any) -> str:
    """The syntax tree as text, like ast.dump without field names, the same on every Python."""
    if isinstance(node, ast.AST):
        parts = [_dump(getattr(node, f, None)) for f in node._fields
                 if not (f in _NEWER_FIELDS and not getattr(node, f, None))]
        return f"{type(node).__name__}({', '.join(parts)})"
    if isinstance(node, list):
        return "[" + ", ".join(_dump(n) for n in node) + "]"
    return repr(node)


def _code_text(fn: types.FunctionType) -> str:
    code = fn.__code__
    return repr((code.co_code, code.co_consts, code.co_names))


def _strip_docstrings(tree: ast.AST) -> None:
    for node in ast.walk(tree):
        body = getattr(node, "body", None)
        if isinstance(body, list):
            node.body = [n for n in body if not (isinstance(n, ast.Expr) and isinstance(n.value, ast.Constant)
                                                 and isinstance(n.value.value, str))] or [ast.Pass()]


def _annotation_nodes(tree: ast.AST):
    """Nodes inside type annotations of functions (they do not compute; dataclass fields'
    annotations stay in the text but their names are not followed either)."""
    for node in ast.walk(tree):
        if isinstance(node, ast.arg) and node.annotation is not None:
            yield from ast.walk(node.annotation)
        elif isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)) and node.returns is not None:
            yield from ast.walk(node.returns)
        elif isinstance(node, ast.AnnAssign):
            yield from ast.walk(node.annotation)


def _attribute_chain(node: ast.Attribute) -> list[str] | None:
    parts = []
    while isinstance(node, ast.Attribute):
        parts.append(node.attr)
        node = node.value
    if not isinstance(node, ast.Name):
        return None
    return [node.id, *reversed(parts)]


def _callables_in(value: Any, depth: int = 0):
    """Functions and classes held in a module-level container (a dispatch table)."""
    if depth > 3:
        return
    if isinstance(value, dict):
        items = list(value.keys()) + list(value.values())
    elif isinstance(value, (list, tuple, set, frozenset)):
        items = list(value)
    else:
        return
    for item in items:
        if isinstance(item, (type, types.FunctionType)):
            yield item
        else:
            yield from _callables_in(item, depth + 1)


def _stable_repr(value: Any, depth: int = 0) -> str:
    """A module-level value as text that does not change between processes."""
    if value is None or isinstance(value, (bool, int, float, complex, str, bytes)):
        return repr(value)
    if isinstance(value, (type, types.FunctionType)):
        return f"<{getattr(value, '__qualname__', type(value).__name__)}>"
    if depth < 4 and isinstance(value, (list, tuple, set, frozenset)):
        items = [_stable_repr(v, depth + 1) for v in value]
        if isinstance(value, (set, frozenset)):
            items.sort()
        return f"{type(value).__name__}[{', '.join(items)}]"
    if depth < 4 and isinstance(value, dict):
        items = sorted(f"{_stable_repr(k, depth + 1)}: {_stable_repr(v, depth + 1)}" for k, v in value.items())
        return "{" + ", ".join(items) + "}"
    tobytes = getattr(value, "tobytes", None)
    if callable(tobytes) and hasattr(value, "dtype"):  # numpy arrays and scalars
        return f"array[{value.dtype}, {getattr(value, 'shape', ())}, {hashlib.sha256(tobytes()).hexdigest()[:16]}]"
    if hasattr(value, "__dataclass_fields__") and not isinstance(value, type):
        fields = {name: getattr(value, name) for name in value.__dataclass_fields__}
        return f"{type(value).__qualname__}({_stable_repr(fields, depth + 1)})"
    import enum

    if isinstance(value, enum.Enum):
        return f"{type(value).__qualname__}.{value.name}"
    # The type's name only: where a standard type lives moves between Pythons (pathlib, 3.13).
    return f"<{type(value).__qualname__}>"
