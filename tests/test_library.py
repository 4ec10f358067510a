"""The library's shape: every module lists its public names in ``__all__``; imports run
down the stages only (io < measured < models < discovery < outputs; lab and runtime beside),
form no circle, and reach no other module's private names."""

import ast
from pathlib import Path

import pytest

LIBRARY = Path(__file__).resolve().parents[1] / "workflow"

STAGES_BELOW = {
    "io": set(),
    "measured": {"io"},
    "models": {"io", "measured"},
    "discovery": {"io", "measured", "models"},
    "outputs": {"io", "measured", "models", "discovery"},
    "lab": {"io", "measured", "models"},
    "runtime": {"io"},
}
"""Stage -> the stages its modules may import (besides their own); the top-level modules
(workflow/api.py, workflow/config.py) may import any."""

MODULES = {
    ".".join(path.relative_to(LIBRARY.parent).with_suffix("").parts).removesuffix(".__init__"): path
    for path in sorted(LIBRARY.rglob("*.py"))
}


def imports_of(path: Path) -> list[tuple[str, list[str]]]:
    """(module, names) of every ``workflow`` import in ``path``, at any depth."""
    found = []
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.ImportFrom) and node.module and node.module.split(".")[0] == "workflow":
            found.append((node.module, [alias.name for alias in node.names]))
        elif isinstance(node, ast.Import):
            found += [(alias.name, []) for alias in node.names if alias.name.split(".")[0] == "workflow"]
    return found


def stage_of(module: str) -> str | None:
    parts = module.split(".")
    return parts[1] if len(parts) > 2 or (len(parts) == 2 and parts[1] in STAGES_BELOW) else None


@pytest.mark.parametrize("module", [m for m, p in MODULES.items() if p.name != "__init__.py"])
def test_all_lists_every_public_function_and_class(module):
    tree = ast.parse(MODULES[module].read_text())
    public = [
        node.name
        for node in tree.body
        if isinstance(node, ast.FunctionDef | ast.ClassDef) and not node.name.startswith("_")
    ]
    listed = [
        [element.value for element in node.value.elts]
        for node in tree.body
        if isinstance(node, ast.Assign) and any(getattr(t, "id", None) == "__all__" for t in node.targets)
    ]
    assert listed, f"{module} has no __all__"
    defined = set(public)
    for node in tree.body:
        targets = node.targets if isinstance(node, ast.Assign) else [getattr(node, "target", None)]
        defined |= {target.id for target in targets if isinstance(target, ast.Name)}
    assert [name for name in public if name not in listed[0]] == []
    assert [name for name in listed[0] if name not in defined] == []


@pytest.mark.parametrize("module", sorted(MODULES))
def test_imports_run_down_the_stages_and_reach_no_private_name(module):
    stage = stage_of(module)
    for imported, names in imports_of(MODULES[module]):
        other = stage_of(imported)
        if stage is not None and other is not None and other != stage:
            assert other in STAGES_BELOW[stage], f"{module} imports {imported}, a stage above its own"
        if imported != module:
            assert [n for n in names if n.startswith("_")] == [], (
                f"{module} imports private names of {imported}"
            )


def test_no_import_circle():
    graph = {
        module: {
            imported if imported in MODULES else imported.rsplit(".", 1)[0]
            for imported, _ in imports_of(path)
        }
        for module, path in MODULES.items()
    }
    # imports of a package's submodules (``from workflow.io import units``) point at the submodule
    for module, path in MODULES.items():
        for imported, names in imports_of(path):
            graph[module] |= {f"{imported}.{name}" for name in names if f"{imported}.{name}" in MODULES}
    graph = {
        module: {m for m in targets if m in MODULES and m != module} for module, targets in graph.items()
    }
    state: dict[str, int] = {}

    def visit(module: str, path: list[str]) -> None:
        state[module] = 1
        for target in sorted(graph[module]):
            assert state.get(target) != 1, "import circle: " + " -> ".join([*path, module, target])
            if target not in state:
                visit(target, [*path, module])
        state[module] = 2

    for module in sorted(graph):
        if module not in state:
            visit(module, [])
