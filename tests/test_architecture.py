"""The house: imports between emaphm's modules, read from the source (module level and
inside functions alike), form no loop where this is checked, so each module can be read
(and imported) after the ones it builds on."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

SRC = Path(__file__).resolve().parents[1] / "src"


def module_name(path: Path) -> str:
    parts = list(path.relative_to(SRC).with_suffix("").parts)
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def imports(path: Path) -> set[str]:
    """The emaphm modules ``path`` imports anywhere in its code (``from .x import y`` counts
    as ``x``, and as ``x.y`` where that is a module)."""
    name = module_name(path)
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    found = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Import):
            found |= {a.name for a in node.names}
        elif isinstance(node, ast.ImportFrom):
            base = package.split(".")
            if node.level:
                base = base[:len(base) - node.level + 1]
                target = ".".join(base + ([node.module] if node.module else []))
            else:
                target = node.module or ""
            found.add(target)
            found |= {f"{target}.{a.name}" for a in node.names}
    return {m for m in found if m.startswith("emaphm")}


def graph(package: str) -> dict[str, set[str]]:
    root = SRC.joinpath(*package.split("."))
    mods = {module_name(p): p for p in root.rglob("*.py")}
    return {m: {t for t in imports(p) if t in mods and t != m} for m, p in mods.items()}


def cycle(g: dict[str, set[str]]) -> list[str] | None:
    state: dict[str, int] = {}
    stack: list[str] = []

    def visit(m: str) -> list[str] | None:
        state[m] = 1
        stack.append(m)
        for t in sorted(g[m]):
            if state.get(t) == 1:
                return stack[stack.index(t):] + [t]
            if t not in state and (found := visit(t)):
                return found
        stack.pop()
        state[m] = 2
        return None

    for m in sorted(g):
        if m not in state and (found := visit(m)):
            return found
    return None


@pytest.mark.parametrize("package", ["emaphm.models", "emaphm.traces"])
def test_no_import_loop_inside(package):
    g = graph(package)
    assert len(g) > 3
    assert cycle(g) is None, " -> ".join(cycle(g))


def test_the_kernels_share_their_constants_from_one_module():
    g = graph("emaphm.models")
    common = "emaphm.models._monitoring_common"
    for kernel in ("monitoring", "monitoring_simd", "step"):
        assert common in g[f"emaphm.models.{kernel}"], kernel
    assert "emaphm.models.monitoring" not in g["emaphm.models.monitoring_simd"]


def test_the_monitoring_step_exists_once():
    """Both kernels run the step of emaphm.models.step; the package has no NumPy copy of
    the monitoring model (the tests keep one as an oracle, tests/monitoring_numpy.py)."""
    g = graph("emaphm.models")
    for kernel in ("monitoring", "monitoring_simd"):
        assert "emaphm.models.step" in g[f"emaphm.models.{kernel}"], kernel
    assert not (SRC / "emaphm" / "models" / "monitoring_numpy.py").exists()
    for path in (SRC / "emaphm").rglob("*.py"):
        text = path.read_text(encoding="utf-8")
        assert "def winding_step(" not in text or path.name == "pmsm.py", path
        assert "def substep(" not in text or path.name == "step.py", path


def test_the_cycle_finder_finds_a_loop():
    assert cycle({"a": {"b"}, "b": {"c"}, "c": {"a"}}) == ["a", "b", "c", "a"]
    assert cycle({"a": {"b"}, "b": set()}) is None
