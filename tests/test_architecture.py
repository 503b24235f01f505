"""The package's shape holds: no import cycles in mtt/, no private names used across modules,
and the command line only parses arguments and dispatches (presentation and data input are
packages of their own that the API uses too).

Read from the source (the AST of every module, imports inside functions included: a lazy
import is still a dependency), so that nothing has to be imported to check it.
"""

from __future__ import annotations

import ast
from pathlib import Path

import networkx as nx
import pytest

ROOT = Path(__file__).resolve().parent.parent


def find_modules(root: Path) -> dict[str, Path]:
    """The modules of the package `root`/mtt by dotted name."""
    found = {}
    for path in sorted((root / "mtt").rglob("*.py")):
        parts = path.relative_to(root).with_suffix("").parts
        found[".".join(parts[:-1] if parts[-1] == "__init__" else parts)] = path
    return found


def _absolute(name: str, package: bool, node: ast.ImportFrom) -> str:
    """The module an ImportFrom names, relative imports resolved."""
    if not node.level:
        return node.module or ""
    base = name.split(".") if package else name.split(".")[:-1]
    base = base[: len(base) - (node.level - 1)]
    return ".".join(base + ([node.module] if node.module else []))


def _type_checking(node: ast.If) -> bool:
    test = node.test
    return (isinstance(test, ast.Name) and test.id == "TYPE_CHECKING") or (
        isinstance(test, ast.Attribute) and test.attr == "TYPE_CHECKING"
    )


def _imports(tree: ast.AST):
    """Every Import and ImportFrom that runs (those under `if TYPE_CHECKING:` do not)."""
    stack = [tree]
    while stack:
        node = stack.pop()
        if isinstance(node, ast.If) and _type_checking(node):
            stack.extend(node.orelse)
            continue
        if isinstance(node, ast.Import | ast.ImportFrom):
            yield node
        stack.extend(ast.iter_child_nodes(node))


def _private(name: str) -> bool:
    return name.startswith("_") and not (name.startswith("__") and name.endswith("__"))


def defined(tree: ast.Module) -> set[str] | None:
    """The names a module defines at its top level (None: any, it has a __getattr__)."""
    names = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef | ast.ClassDef):
            names.add(node.name)
        elif isinstance(node, ast.Name) and isinstance(node.ctx, ast.Store):
            names.add(node.id)
        elif isinstance(node, ast.alias):
            names.add(node.asname or node.name.partition(".")[0])
    return None if "__getattr__" in names else names


def analyse(root: Path) -> tuple[nx.DiGraph, list[str], list[str]]:
    """The graph of imports between the modules of `root`/mtt, every private name one
    module takes from another (`from mtt.a import _x`, or `a._x` on an imported module `a`),
    and every name imported from a module of mtt that does not define it (a lazy import
    fails only when its function runs)."""
    modules = find_modules(root)
    trees = {
        name: ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
        for name, path in modules.items()
    }
    graph = nx.DiGraph()
    graph.add_nodes_from(modules)
    private, missing = [], []
    for name, path in modules.items():
        tree = trees[name]
        aliases = {}  # a name bound to an mtt module -> that module
        for node in _imports(tree):
            where = f"{path.relative_to(root)}:{node.lineno}"
            if isinstance(node, ast.Import):
                for alias in node.names:
                    if alias.name in modules:
                        graph.add_edge(name, alias.name)
                        aliases[alias.asname or alias.name] = alias.name
                continue
            source = _absolute(name, path.name == "__init__.py", node)
            if source not in modules:
                continue
            for alias in node.names:
                submodule = f"{source}.{alias.name}"
                if submodule in modules:
                    graph.add_edge(name, submodule)
                    aliases[alias.asname or alias.name] = submodule
                    continue
                graph.add_edge(name, source)
                names = defined(trees[source])
                if names is not None and alias.name not in names:
                    missing.append(f"{where}: {alias.name} from {source}")
                if _private(alias.name) and source != name:
                    private.append(f"{where}: {alias.name} from {source}")
        for node in ast.walk(tree):
            if (
                isinstance(node, ast.Attribute)
                and isinstance(node.value, ast.Name)
                and node.value.id in aliases
                and aliases[node.value.id] != name
                and _private(node.attr)
            ):
                where = f"{path.relative_to(root)}:{node.lineno}"
                private.append(f"{where}: {node.attr} of {aliases[node.value.id]}")
    graph.remove_edges_from(nx.selfloop_edges(graph))
    return graph, private, missing


MODULES = find_modules(ROOT)
GRAPH, PRIVATE, MISSING = analyse(ROOT)


def test_no_import_cycles_in_mtt():
    cycles = [" -> ".join([*cycle, cycle[0]]) for cycle in nx.simple_cycles(GRAPH)]
    assert not cycles, "import cycles:\n" + "\n".join(sorted(cycles))


def test_no_private_name_is_used_across_modules():
    assert not PRIVATE, "private names used across modules:\n" + "\n".join(PRIVATE)


def test_every_name_imported_from_mtt_exists():
    assert not MISSING, "imported but not defined:\n" + "\n".join(MISSING)


def test_only_the_command_line_imports_the_command_line():
    outside = [
        f"{name} imports {target}"
        for name, target in GRAPH.edges
        if target.startswith("mtt.cli") and not name.startswith("mtt.cli")
        and name != "mtt.__main__"
    ]  # fmt: skip
    assert not outside, "\n".join(outside)


def test_modules_stay_small():
    """A module over ~400 lines is a sign to split it (the developers' guide)."""
    long = {
        str(path.relative_to(ROOT)): lines
        for path in MODULES.values()
        if (lines := len(path.read_text(encoding="utf-8").splitlines())) > 400
    }
    assert not long, long


def _third_party(tree: ast.AST) -> set[str]:
    """The top-level packages outside mtt that a module imports (lazily or not)."""
    found = set()
    for node in _imports(tree):
        if isinstance(node, ast.Import):
            found |= {alias.name.partition(".")[0] for alias in node.names}
        elif not node.level and node.module:
            found.add(node.module.partition(".")[0])
    return found - {"mtt", "__future__"}


# the libraries that compute (algebra, numbers, graphs, parsing, templates, figures)
COMPUTING = {"sympy", "numpy", "scipy", "networkx", "lark", "jinja2", "matplotlib"}
# what the command line may still take from them, and why
CLI_COMPUTING = {
    "mtt.cli.running": {"numpy"},  # np.errstate: no floating-point warnings while a command runs
    "mtt.cli.unknowns": {"numpy"},  # the unknowns' values as the generated module takes them
}


def test_the_command_line_computes_nothing():
    """mtt/cli only parses arguments and dispatches: it imports none of the libraries that
    compute (the stages, mtt.present, mtt.data and mtt.api do), but for CLI_COMPUTING."""
    found = {}
    for name, path in MODULES.items():
        if name == "mtt.cli" or name.startswith("mtt.cli."):
            tree = ast.parse(path.read_text(encoding="utf-8"))
            used = (_third_party(tree) & COMPUTING) - CLI_COMPUTING.get(name, set())
            if used:
                found[name] = sorted(used)
    assert not found, found


# presentation the API does not offer yet (`mtt identifiability`'s text: the API gives the
# Identifiability itself): each leaves this list when the API uses it too
CLI_ONLY_PRESENTATION = {"mtt.present.identifiability"}


def test_presentation_and_data_input_serve_more_than_the_command_line():
    """mtt.present and mtt.data are packages that the API and the command line both use:
    each of their modules is imported from outside mtt/cli (the API, mtt.batch, or another
    such module), unless it is listed in CLI_ONLY_PRESENTATION."""
    shared = [name for name in MODULES if name.startswith(("mtt.present.", "mtt.data."))]
    alone = sorted(
        name
        for name in shared
        if name not in CLI_ONLY_PRESENTATION
        and not any(not user.startswith("mtt.cli") for user in GRAPH.predecessors(name))
    )
    assert not alone, f"used by the command line only: {alone}"
    stale = sorted(name for name in CLI_ONLY_PRESENTATION if name not in MODULES or any(
        not user.startswith("mtt.cli") for user in GRAPH.predecessors(name)))  # fmt: skip
    assert not stale, f"CLI_ONLY_PRESENTATION lists modules used beyond the CLI: {stale}"


CYCLE = {
    "mtt/__init__.py": "",
    "mtt/a.py": "from mtt import b\n",
    "mtt/b.py": "def f():\n    from mtt.c import _helper\n",
    "mtt/c.py": "import mtt.a\n_helper = 1\n",
    "mtt/e.py": "def f():\n    from mtt.c import gone\n",
    "mtt/d.py": "from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n    from mtt import a\n"
    "from mtt import c\nx = c._helper\n",
}


@pytest.mark.parametrize("lazy", [True, False])
def test_the_checks_find_a_cycle_and_a_private_name(tmp_path, lazy):
    """The checks themselves: a cycle through a lazy import, and private names taken both
    ways, are found; an import under TYPE_CHECKING is not a dependency."""
    for relative, text in CYCLE.items():
        path = tmp_path / relative
        path.parent.mkdir(exist_ok=True)
        path.write_text(text if lazy else text.replace("def f():\n    ", ""))
    graph, private, missing = analyse(tmp_path)
    assert list(nx.simple_cycles(graph)) and not graph.has_edge("mtt.d", "mtt.a")
    assert [line.split(": ", 1)[1] for line in missing] == ["gone from mtt.c"]
    assert [line.split(": ", 1)[1] for line in private] == [
        "_helper from mtt.c",
        "_helper of mtt.c",
    ]
