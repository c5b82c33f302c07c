"""The layout's promises, read from the code's own imports (docs/design.md, "Layout").

- No import circle anywhere, counting imports inside functions.
- Imports point one way: ``benchmarks`` -> ``training`` -> ``expert`` -> ``fetchcarry_env``
  (measurement sits outside the three packages, and none of them imports it).
- An import inside a function only where it keeps a heavy or optional dependency
  (torch, stable-baselines3, Minari, Ray, matplotlib, SCIP) out of ``import
  fetchcarry_env``, ``import training`` and the command line's start-up.
- No function longer than 100 lines.

``python tests/test_architecture.py`` prints the figures (circles, local imports,
functions over 50 and 100 lines).
"""

from __future__ import annotations

import ast
import sys
from dataclasses import dataclass, field
from functools import cache
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
PACKAGES = ("fetchcarry_env", "expert", "training", "benchmarks")
HEAVY = {
    "torch",
    "stable_baselines3",
    "sb3_contrib",
    "minari",
    "h5py",
    "ray",
    "matplotlib",
    "PIL",
    "pyscipopt",
    "pybullet",
    "scipy",
    "highspy",
    "ortools",
}
"""Third-party packages that are slow to import or optional: the only reason for an import inside a function."""
LONGEST_FUNCTION = 100  # lines, docstring included
LAYERS = {"fetchcarry_env": 0, "expert": 1, "training": 2, "benchmarks": 3}  # a package imports only lower layers


@dataclass
class Module:
    name: str
    path: Path
    top: set[str] = field(default_factory=set)  # modules (project or third-party roots) imported at the top
    local: list[tuple[int, tuple[str, ...]]] = field(default_factory=list)  # (line, modules) of imports in functions


def _module_name(path: Path) -> str:
    parts = path.relative_to(ROOT).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _targets(node: ast.Import | ast.ImportFrom, current: str, is_package: bool, known: set[str]) -> list[str]:
    """The modules an import statement loads: project modules by full name, others by their root package."""
    if isinstance(node, ast.Import):
        names = [alias.name for alias in node.names]
    else:
        base = node.module or ""
        if node.level:
            parts = current.split(".")[: len(current.split(".")) - node.level + (1 if is_package else 0)]
            base = ".".join([*parts, base] if base else parts)
        names = [base] + [f"{base}.{alias.name}" for alias in node.names if f"{base}.{alias.name}" in known]
    return [name if name in known else name.split(".")[0] for name in names]


@cache
def modules() -> dict[str, Module]:
    """Every module of the three packages, with its top-level and function-local imports."""
    paths = [path for package in PACKAGES for path in (ROOT / package).rglob("*.py")]
    known = {_module_name(path) for path in paths}
    found = {}
    for path in paths:
        module = Module(_module_name(path), path)
        tree = ast.parse(path.read_text(), filename=str(path))
        _collect(tree, module, path.name == "__init__.py", known, inside=False)
        found[module.name] = module
    return found


def _collect(node: ast.AST, module: Module, is_package: bool, known: set[str], inside: bool) -> None:
    for child in ast.iter_child_nodes(node):
        if isinstance(child, ast.If) and _is_type_checking(child.test):
            continue  # imports for type hints only never run
        if isinstance(child, ast.Import | ast.ImportFrom):
            targets = tuple(t for t in _targets(child, module.name, is_package, known) if t != module.name)
            if inside:
                module.local.append((child.lineno, targets))
            else:
                module.top.update(targets)
        function = isinstance(child, ast.FunctionDef | ast.AsyncFunctionDef | ast.Lambda)
        _collect(child, module, is_package, known, inside or function)


def _is_type_checking(test: ast.expr) -> bool:
    return (isinstance(test, ast.Name) and test.id == "TYPE_CHECKING") or (
        isinstance(test, ast.Attribute) and test.attr == "TYPE_CHECKING"
    )


def _imported(module: Module) -> set[str]:
    """Every module ``module`` imports, at its top or inside functions."""
    return module.top | {target for _, targets in module.local for target in targets}


def circles() -> list[list[str]]:
    """The strongly connected components of more than one module (Tarjan), imports inside functions counted."""
    graph = {name: {t for t in _imported(m) if t in modules()} for name, m in modules().items()}
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    found: list[list[str]] = []

    def visit(node: str) -> None:
        index[node] = low[node] = len(index)
        stack.append(node)
        for target in graph[node]:
            if target not in index:
                visit(target)
                low[node] = min(low[node], low[target])
            elif target in stack:
                low[node] = min(low[node], index[target])
        if low[node] == index[node]:
            component = []
            while True:
                member = stack.pop()
                component.append(member)
                if member == node:
                    break
            if len(component) > 1:
                found.append(sorted(component))

    sys.setrecursionlimit(max(sys.getrecursionlimit(), 10_000))
    for name in graph:
        if name not in index:
            visit(name)
    return found


@cache
def is_heavy(name: str) -> bool:
    """Whether importing ``name`` loads a heavy or optional package (at its top, or through the modules it imports)."""
    if name not in modules():
        return name in HEAVY
    seen, todo = set(), [name]
    while todo:
        current = todo.pop()
        if current in seen:
            continue
        seen.add(current)
        if current not in modules():
            if current in HEAVY:
                return True
            continue
        todo.extend(modules()[current].top)
    return False


CHECKOUT_STUDIES = ("benchmarks.studies.octagon_rule_study", "benchmarks.studies.ppo_speed.mask_ab")
"""A/B studies that import the project inside a function on purpose: after putting one checkout on the path."""


def needless_local_imports() -> list[str]:
    """Imports inside functions of light modules: they belong at the top."""
    return [
        f"{m.path.relative_to(ROOT)}:{line} imports {', '.join(targets)}"
        for m in modules().values()
        if m.name not in CHECKOUT_STUDIES
        for line, targets in m.local
        if not any(is_heavy(target) for target in targets)
    ]


def function_lengths() -> list[tuple[int, str]]:
    """(lines, place) of every function, longest first."""
    lengths = []
    for m in modules().values():
        for node in ast.walk(ast.parse(m.path.read_text())):
            if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
                lengths.append(
                    (node.end_lineno - node.lineno + 1, f"{m.path.relative_to(ROOT)}:{node.lineno} {node.name}")
                )
    return sorted(lengths, reverse=True)


def test_no_import_circle() -> None:
    assert circles() == []


def test_imports_point_one_way() -> None:
    upward = [
        f"{m.name} imports {target}"
        for m in modules().values()
        for target in _imported(m)
        if target in modules() and LAYERS[target.split(".")[0]] > LAYERS[m.name.split(".")[0]]
    ]
    assert upward == []


def test_imports_inside_functions_only_for_heavy_dependencies() -> None:
    assert needless_local_imports() == []


def test_no_function_over_100_lines() -> None:
    assert [place for lines, place in function_lengths() if lines > LONGEST_FUNCTION] == []


if __name__ == "__main__":
    lengths = function_lengths()
    local = sum(len(m.local) for m in modules().values())
    print(f"import circles: {len(circles())}  {circles()}")
    print(f"imports inside functions: {local} ({len(needless_local_imports())} of light modules)")
    print(f"functions over 50 lines: {sum(n > 50 for n, _ in lengths)}; over 100: {sum(n > 100 for n, _ in lengths)}")
    for line in needless_local_imports():
        print("  light local import:", line)
    for lines, place in lengths[:10]:
        print(f"  {lines:4d} {place}")
