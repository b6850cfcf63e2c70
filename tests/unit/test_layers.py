"""The package's layers (docs/architecture.md): each folder imports only from folders below it,
counting imports inside functions; no import circles among the modules; the engine imports
nothing of railride outside itself; importing the parameter classes loads no numba."""

from __future__ import annotations

import ast
import subprocess
import sys
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[2] / "railride"
#: bottom to top; the modules directly in railride/ are the ground floor
LAYERS = (
    "ground",
    "engine",
    "model",
    "secondary",
    "analysis",
    "plots",
    "output",
    "run",
    "frequency",
    "studies",
    "testing",
    "cli",
)


def _modules() -> dict[str, Path]:
    found = {}
    for path in PACKAGE.rglob("*.py"):
        parts = list(path.relative_to(PACKAGE.parent).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts = parts[:-1]
        found[".".join(parts)] = path
    return found


MODULES = _modules()


def _home(name: str) -> str | None:
    while name and name not in MODULES:
        name = name.rpartition(".")[0]
    return name or None


def _imports(module: str) -> dict[str, int]:
    """The railride modules ``module`` imports (anywhere in it), with a line of each."""
    path = MODULES[module]
    base = module if path.name == "__init__.py" else module.rpartition(".")[0]
    out: dict[str, int] = {}
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Import):
            targets = [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                b = base
                for _ in range(node.level - 1):
                    b = b.rpartition(".")[0]
                mod = f"{b}.{node.module}" if node.module else b
            else:
                mod = node.module or ""
            targets = [mod, *(f"{mod}.{a.name}" for a in node.names)]
        else:
            continue
        for target in targets:
            home = _home(target) if target.startswith("railride") else None
            # the package's face re-exports every public name lazily; nothing inside imports it
            if home and home not in (module, "railride"):
                out.setdefault(home, node.lineno)
    return out


def layer(module: str) -> str:
    parts = module.split(".")
    return parts[1] if len(parts) > 2 or (len(parts) == 2 and parts[1] in LAYERS) else "ground"


GRAPH = {m: _imports(m) for m in MODULES if m != "railride"}


def test_every_module_sits_on_a_known_floor():
    assert {layer(m) for m in GRAPH} <= set(LAYERS)
    assert len(GRAPH) > 80  # the walk found the package


def test_no_import_runs_up_a_floor():
    up = [
        f"{m}:{line} imports {t} ({layer(m)} < {layer(t)})"
        for m, targets in GRAPH.items()
        for t, line in targets.items()
        if t != "railride" and LAYERS.index(layer(t)) > LAYERS.index(layer(m)) and m != "railride.__main__"
    ]
    assert not up, "\n".join(up)


def test_no_import_circles():
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    circles = []

    def visit(v: str) -> None:  # Tarjan's strongly connected components
        index[v] = low[v] = len(index)
        stack.append(v)
        for w in GRAPH.get(v, {}):
            if w not in GRAPH:
                continue
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            part = []
            while True:
                w = stack.pop()
                part.append(w)
                if w == v:
                    break
            if len(part) > 1:
                circles.append(sorted(part))

    sys.setrecursionlimit(max(sys.getrecursionlimit(), 10_000))
    for v in GRAPH:
        if v not in index:
            visit(v)
    assert not circles, circles


def test_the_engine_imports_nothing_above_it():
    leaks = [(m, t) for m in GRAPH if layer(m) == "engine" for t in GRAPH[m] if layer(t) != "engine"]
    assert not leaks


@pytest.mark.parametrize("folder,limit", [("engine", 900), ("other", 700)])
def test_module_sizes(folder, limit):
    big = {
        m: n
        for m, p in MODULES.items()
        if (layer(m) == "engine") == (folder == "engine")
        and (n := len(p.read_text(encoding="utf-8").splitlines())) > limit
    }
    assert not big


def test_the_parameter_classes_load_no_numba():
    code = (
        "import sys; import railride as rr; rr.VehicleParams; rr.Suspension; rr.GainSet; rr.DamperFault; rr.dampers; "
        "import railride.secondary.sensing; print('numba' in sys.modules)"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "False"
