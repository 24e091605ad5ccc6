"""The house, read from the source: imports between emaphm's modules (module level and
inside functions alike) form no loop but the known ones (:data:`KNOWN_LOOPS`), so each
module can be read (and imported) after the ones it builds on, and none reaches a layer
above its own (:data:`LAYERS`) but the known ones (:data:`KNOWN_UPWARD`); the architecture
page draws every package; no function outside the numerical kernels is over 100 lines; no
private name is imported from another package; seeds are checked only by
:mod:`emaphm.seeds`; a fault mode's name is written only in its own module. Each rule is
also run on a small case it must catch."""

from __future__ import annotations

import ast
import sys
from collections import deque
from pathlib import Path

import pytest

SRC = Path(__file__).resolve().parents[1] / "src"


def module_name(path: Path) -> str:
    parts = list(path.relative_to(SRC).with_suffix("").parts)
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def import_statements(path: Path):
    """``(line, module, names)`` of every import anywhere in ``path``'s code, relative
    imports resolved: ``import x`` gives ``names`` None, ``from .x import a, b`` the module
    ``<package>.x`` and ``["a", "b"]``."""
    name = module_name(path)
    package = package_of(name, path)
    for node in _code_nodes(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Import):
            for a in node.names:
                yield node.lineno, a.name, None
        elif isinstance(node, ast.ImportFrom):
            base = package.split(".")
            if node.level:
                base = base[:len(base) - node.level + 1]
                target = ".".join(base + ([node.module] if node.module else []))
            else:
                target = node.module or ""
            yield node.lineno, target, [a.name for a in node.names]


def _code_nodes(tree: ast.AST):
    """Every node of ``tree`` but those under ``if TYPE_CHECKING:`` (annotations only:
    never imported when the code runs)."""
    todo = deque([tree])                # breadth first, as ast.walk
    while todo:
        node = todo.popleft()
        yield node
        for child in ast.iter_child_nodes(node):
            if isinstance(child, ast.If) and _is_type_checking(child.test):
                todo.extend(child.orelse)
                continue
            todo.append(child)


def _is_type_checking(test: ast.AST) -> bool:
    return (isinstance(test, ast.Name) and test.id == "TYPE_CHECKING") or \
        (isinstance(test, ast.Attribute) and test.attr == "TYPE_CHECKING")


def imports(path: Path) -> set[str]:
    """The emaphm modules ``path`` imports anywhere in its code (``from .x import y`` counts
    as ``x``, and as ``x.y`` where that is a module)."""
    found = set()
    for _, target, names in import_statements(path):
        found.add(target)
        found |= {f"{target}.{n}" for n in names or ()}
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


#: The import loops emaphm keeps, each edge with its reason; any other loop over the whole
#: package, through a lazy import or not, fails :func:`test_no_import_loop_in_emaphm`.
KNOWN_LOOPS = {
    # a list of traces is a batch (issue 34): the one-trace function hands it to the batch
    # module, which runs the one-trace function on workers
    ("emaphm.identify", "emaphm.batch"): "identify([t1, t2]) is identify_many",
    ("emaphm.verdict", "emaphm.batch"): "examine([t1, t2]) is examine_many",
    # emaphm.prognosis.history.inspect of 0.3, kept one release with a DeprecationWarning
    ("emaphm.prognosis.history", "emaphm.prognosis.workflow"): "the 0.3 name, deprecated",
}


def test_no_import_loop_in_emaphm():
    """Over every module, imports inside functions included (type-checking ones excluded),
    the known loops' edges aside: no loop."""
    g = graph("emaphm")
    assert len(g) > 100
    for (a, b), why in KNOWN_LOOPS.items():
        assert b in g[a], f"{a} -> {b} ({why}) is gone: take it off KNOWN_LOOPS"
        g[a] = g[a] - {b}
    assert cycle(g) is None, " -> ".join(cycle(g))


def test_a_loop_through_a_lazy_import_is_found(tmp_path, monkeypatch):
    """The rule sees an import inside a function, and not one under TYPE_CHECKING."""
    files = {"emaphm/__init__.py": "",
             "emaphm/low.py": "def f():\n    from .high import g\n    return g()\n",
             "emaphm/high.py": "from .low import f\n",
             "emaphm/typed.py": "from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n"
                                "    from .user import U\n",
             "emaphm/user.py": "from .typed import TYPE_CHECKING\n"}
    for name, text in files.items():
        (tmp_path / name).parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / name).write_text(text)
    monkeypatch.setattr(sys.modules[__name__], "SRC", tmp_path)
    g = graph("emaphm")
    assert cycle(g) in (["emaphm.high", "emaphm.low", "emaphm.high"],
                        ["emaphm.low", "emaphm.high", "emaphm.low"])
    assert "emaphm.user" not in g["emaphm.typed"]


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


# ----------------------------------------------------------------------------- the rules of the house

def modules() -> dict[str, Path]:
    """Every module of emaphm by name."""
    return {module_name(p): p for p in sorted((SRC / "emaphm").rglob("*.py"))}


def package_of(name: str, path: Path) -> str:
    """The package a module lives in: the folder that holds it (``emaphm`` for the top-level
    modules, ``emaphm.traces.importers`` for ``emaphm.traces.importers.mdf``)."""
    return name if path.name == "__init__.py" else name.rpartition(".")[0]


#: The numerical kernels allowed over :data:`MAX_LINES` lines, by ``path:qualified name``
#: (each is Numba-compiled: one function, so that the compiler sees the whole loop).
LONG_KERNELS = {
    "emaphm/models/reference.py:_rm_kernel": "the reference plant's time loop (Numba)",
}
MAX_LINES = 100


def functions(tree: ast.AST, prefix: str = ""):
    """``(qualified name, node)`` of every function in ``tree``, methods and nested ones too."""
    for node in ast.iter_child_nodes(tree):
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
            name = f"{prefix}{node.name}"
            if not isinstance(node, ast.ClassDef):
                yield name, node
            yield from functions(node, f"{name}.")
        else:
            yield from functions(node, prefix)


def long_functions(path: Path) -> dict[str, int]:
    """``path:qualified name -> lines`` of the functions of ``path`` over MAX_LINES lines
    (from ``def`` to the last line of the body, docstring included)."""
    rel = path.relative_to(SRC).as_posix()
    found = {}
    for name, node in functions(ast.parse(path.read_text(encoding="utf-8"))):
        lines = node.end_lineno - node.lineno + 1
        if lines > MAX_LINES:
            found[f"{rel}:{name}"] = lines
    return found


def test_no_function_outside_the_numerical_kernels_is_over_100_lines():
    long = {}
    for path in modules().values():
        long |= long_functions(path)
    over = {k: n for k, n in long.items() if k not in LONG_KERNELS}
    assert over == {}, f"functions over {MAX_LINES} lines (split them): {over}"
    stale = sorted(set(LONG_KERNELS) - set(long))
    assert stale == [], f"LONG_KERNELS names functions no longer over {MAX_LINES} lines: {stale}"
    for key in LONG_KERNELS:                      # an exemption is a compiled kernel
        rel, name = key.split(":")
        node = dict(functions(ast.parse((SRC / rel).read_text(encoding="utf-8"))))[name]
        assert any("jit" in ast.unparse(d) for d in node.decorator_list), key


def test_the_length_rule_sees_methods_and_nested_functions():
    body = "\n".join(f"    x{i} = {i}" for i in range(MAX_LINES))
    text = f"class A:\n  def m(self):\n{body}\n\ndef f():\n  def g():\n{body}\n  return g\n"
    lines = {name: node.end_lineno - node.lineno + 1 for name, node in functions(ast.parse(text))}
    assert lines["A.m"] == MAX_LINES + 1 and lines["f.g"] == MAX_LINES + 1
    assert lines["f"] == MAX_LINES + 3


# Private names. A name that starts with an underscore belongs to its package (the folder
# that holds its module): other modules of that package may import it, modules of another
# package may not (make it public, or move the code). A private *module* is its package's
# too: ``emaphm.models._jit`` is for ``emaphm.models``. The top-level private modules
# (``emaphm._cli_common``, ``_files``, ``_text``, ``_sqlite``, ``_lazy``) are emaphm's own
# shared infrastructure, private to the distribution, not to a folder: every package may
# import their public names, never their private ones.

def imported_names(path: Path, mods: dict[str, Path]):
    """``(line, module, imported name or None)`` of every emaphm import of ``path`` (a
    module of ``mods``); ``module`` is the module the name comes from (the name
    itself where it is a module)."""
    for line, target, names in import_statements(path):
        if not target.startswith("emaphm"):
            continue
        if names is None:
            yield line, target, None
        for a in names or ():
            full = f"{target}.{a}"
            yield (line, full, None) if full in mods else (line, target, a)


def private_imports() -> list[str]:
    mods = modules()
    found = []
    for name, path in mods.items():
        here = package_of(name, path)
        for line, module, imported in imported_names(path, mods):
            owner = package_of(module, mods[module]) if module in mods else module
            parts = module.split(".")
            private_module = any(p.startswith("_") and not p.startswith("__") for p in parts)
            shared = owner == "emaphm" and len(parts) == 2        # emaphm._files and kin
            private_name = imported is not None and imported.startswith("_") \
                and not imported.startswith("__")
            if owner == here:
                continue
            if private_name or (private_module and not shared):
                found.append(f"{name}:{line}: {module}" + (f" import {imported}" if imported else ""))
    return found


def test_no_private_name_is_imported_across_packages():
    found = private_imports()
    assert found == [], "private names imported from another package (make them public, or " \
                        "move the code):\n" + "\n".join(found)


def test_the_private_import_rule_reads_every_kind_of_import(tmp_path, monkeypatch):
    """The rule on a small tree of its own: the same package may share private names, the
    top-level private modules are shared by all, a subpackage's private module is its own."""
    src = tmp_path / "src"
    files = {
        "emaphm/__init__.py": "",
        "emaphm/_files.py": "def atomic_write(): pass\ndef _tmp(): pass\n",
        "emaphm/a/__init__.py": "",
        "emaphm/a/_kern.py": "def run(): pass\n",
        "emaphm/a/x.py": "def _helper(): pass\nfrom ._kern import run\n",
        "emaphm/a/y.py": "from .x import _helper\nfrom .._files import atomic_write\n",
        "emaphm/b/__init__.py": "",
        "emaphm/b/z.py": ("from ..a.x import _helper\nfrom emaphm.a import _kern\n"
                          "import emaphm.a._kern\nfrom .._files import _tmp, atomic_write\n"),
    }
    for rel, text in files.items():
        (src / rel).parent.mkdir(parents=True, exist_ok=True)
        (src / rel).write_text(text, encoding="utf-8")
    monkeypatch.setattr(sys.modules[__name__], "SRC", src)
    assert private_imports() == ["emaphm.b.z:1: emaphm.a.x import _helper",
                                 "emaphm.b.z:2: emaphm.a._kern",
                                 "emaphm.b.z:3: emaphm.a._kern",
                                 "emaphm.b.z:4: emaphm._files import _tmp"]


# Seeds: one check, emaphm.seeds.check_seed (and as_generator, which calls it). A copy
# elsewhere (isinstance on a seed, a seed compared with a number) drifts from it.

def seed_checks(path: Path) -> list[int]:
    """Lines of ``path`` that check a seed by hand: ``isinstance(<seed>, ...)`` or a seed
    compared with a number, where ``<seed>`` is a name or attribute that says seed."""
    def says_seed(node: ast.AST) -> bool:
        name = node.id if isinstance(node, ast.Name) else \
            node.attr if isinstance(node, ast.Attribute) else ""
        return "seed" in name.lower()

    lines = []
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Call) and isinstance(node.func, ast.Name) \
                and node.func.id == "isinstance" and node.args and says_seed(node.args[0]):
            lines.append(node.lineno)
        elif isinstance(node, ast.Compare):
            sides = [node.left, *node.comparators]
            if any(says_seed(s) for s in sides) and any(
                    isinstance(s, ast.Constant) and type(s.value) in (int, float) for s in sides):
                lines.append(node.lineno)
    return lines


def test_seeds_are_checked_only_by_emaphm_seeds():
    found = {name: lines for name, path in modules().items()
             if name != "emaphm.seeds" and (lines := seed_checks(path))}
    assert found == {}, f"seeds checked by hand (use emaphm.seeds.check_seed): {found}"
    assert seed_checks(SRC / "emaphm" / "seeds.py"), "the seed rule no longer sees the one check"


# ----------------------------------------------------------------------------- one vocabulary
#: Where a mode's or an indicator's name may stand as a string outside its own module, and
#: why: each is a parameter or the paper's scenario vocabulary that shares the word, not the
#: mode (issue 33's rule).
VOCABULARY_EXCEPTIONS = {
    # the paper's fault vector: its components' names ("friction", "backlash", "short_a")
    # name the parameters k1.. of Eq. 1, and its scenarios ("friction-high") the paper's rows
    "emaphm/faults.py": {"friction", "backlash", "short_a", "short_b", "short_c",
                         "eccentricity"},
    # the paper's Table 3, row by row as it prints them (its scenarios' words)
    "emaphm/campaign/report.py": {"friction", "backlash", "eccentricity"},
    # relative deviations of a unit's parameters from its data sheet: the dry friction's
    "emaphm/calibration.py": {"friction"},
    "emaphm/units.py": {"friction"},
    # the transmission's backlash width [rad], a field of Transmission
    "emaphm/params.py": {"backlash"},
    # the kind of a physical quantity (ohm), as units and data sheets name it
    "emaphm/quantities.py": {"resistance"},
    "emaphm/datasheet.py": {"resistance"},
    # the registry lists its modules by name
    "emaphm/modes/__init__.py": {"friction", "backlash", "short_circuit", "eccentricity",
                                 "gain_drift", "demagnetization", "current_sensor", "resistance"},
}


def vocabulary_literals(path: Path, names: set[str]) -> list[tuple[int, str]]:
    """The string constants of ``path`` that are one of ``names`` (docstrings and
    f-string text included: a name written in words is a constant too)."""
    return [(n.lineno, n.value) for n in ast.walk(ast.parse(path.read_text(encoding="utf-8")))
            if isinstance(n, ast.Constant) and isinstance(n.value, str) and n.value in names]


def test_no_mode_or_indicator_name_is_written_outside_its_mode():
    """The fault vocabulary lives in emaphm.modes: everything else reads it from the
    registry (a threshold field as an attribute, an indicator from its mode's module)."""
    from emaphm import modes

    names = set(modes.MODES) | set(modes.INDICATORS) | set(modes.INDICATOR_ALIASES)
    found = []
    for path in sorted((SRC / "emaphm").rglob("*.py")):
        rel = path.relative_to(SRC).as_posix()
        for line, value in vocabulary_literals(path, names):
            mode_of = modes.INDICATOR_MODE.get(modes.INDICATOR_ALIASES.get(value, value), value)
            if rel == f"emaphm/modes/{mode_of}.py" or value in VOCABULARY_EXCEPTIONS.get(rel, ()):
                continue
            found.append(f"{rel}:{line}: {value!r}")
    assert not found, "a mode's name written outside its module:\n" + "\n".join(found)


def test_the_vocabulary_rule_finds_a_name(tmp_path):
    bad = tmp_path / "bad.py"
    bad.write_text('LABELS = {"gain_drift": "gain", "x": 1}\nif m == "short_circuit_a": pass\n')
    assert vocabulary_literals(bad, {"gain_drift", "short_circuit_a"}) == [
        (1, "gain_drift"), (2, "short_circuit_a")]


# ----------------------------------------------------------------------------- the layers
#: Each module's layer, as docs/architecture.md draws them (a module takes its longest
#: prefix's): a module imports only its own layer and those below it, imports inside
#: functions included (:func:`test_no_upward_import`).
LAYERS = {
    # shared infrastructure and the package's lazy index
    "emaphm": 0, "emaphm._text": 0, "emaphm._files": 0, "emaphm._sqlite": 0, "emaphm._lazy": 0,
    "emaphm.seeds": 0, "emaphm.logs": 0, "emaphm.quantities": 0, "emaphm.frames": 0,
    "emaphm.progress": 0,
    "emaphm.traces": 1,
    # the vocabulary
    "emaphm.params": 2, "emaphm.firmware": 2, "emaphm.profiles": 2,
    "emaphm.faults": 3, "emaphm.datasheet": 3, "emaphm.units": 3, "emaphm.acquisition": 3,
    "emaphm.modes": 4,
    "emaphm.traces.importers": 5,       # bench exports: channel maps read parameters
    "emaphm.optim": 5,
    "emaphm.models": 6,
    "emaphm.simulate": 7, "emaphm.diagnosis": 7, "emaphm.fitness": 7, "emaphm.search": 7,
    "emaphm.calibration": 8, "emaphm.recorded": 8,
    "emaphm.problem": 9, "emaphm.identify": 10, "emaphm.fault_loops": 10.5, "emaphm.verdict": 11,
    "emaphm.campaign.executors": 11.5,  # the worker pools batch and the campaigns share
    "emaphm.batch": 12, "emaphm.results": 12, "emaphm.plots": 12, "emaphm.mismatch": 12,
    "emaphm.prognosis": 13, "emaphm.assessment": 14, "emaphm.campaign": 14, "emaphm.fleet": 15,
    "emaphm._cli_common": 16,
    "emaphm.cli": 17, "emaphm.prognosis.cli": 17, "emaphm.campaign.cli": 17,
    "emaphm.fleet.cli": 17, "emaphm.assessment.cli": 17, "emaphm.traces.importers.cli": 17,
    "emaphm.__main__": 18,
}

#: The upward imports emaphm keeps, each with its reason (all inside functions); any other
#: fails :func:`test_no_upward_import`.
KNOWN_UPWARD = {
    ("emaphm.identify", "emaphm.batch"): "identify([t1, t2]) is identify_many (KNOWN_LOOPS)",
    ("emaphm.verdict", "emaphm.batch"): "examine([t1, t2]) is examine_many (KNOWN_LOOPS)",
    ("emaphm.params", "emaphm.modes"): "a parameter file's [thresholds] are the modes' "
                                       "Thresholds fields, checked when it is read",
    ("emaphm.traces.files", "emaphm.traces.importers.registry"):
        "a refused bench export's suffix points to emaphm import",
}


def layer(module: str) -> float | None:
    """``module``'s layer: its longest prefix's in :data:`LAYERS` (None: unranked)."""
    parts = module.split(".")
    for i in range(len(parts), 0, -1):
        found = LAYERS.get(".".join(parts[:i]))
        if found is not None:
            return found
    return None


def upward(g: dict[str, set[str]]) -> list[tuple[str, str]]:
    return sorted((a, b) for a, ts in g.items() for b in ts if layer(b) > layer(a))


def test_no_upward_import():
    g = graph("emaphm")
    assert not [m for m in g if layer(m) is None], "a module of no layer: add it to LAYERS"
    found = upward(g)
    gone = [e for e in KNOWN_UPWARD if e not in found]
    assert not gone, f"{gone} no longer import upward: take them off KNOWN_UPWARD"
    new = [f"{a} -> {b} ({layer(a):g} -> {layer(b):g})" for a, b in found
           if (a, b) not in KNOWN_UPWARD]
    assert not new, "an import upward:\n" + "\n".join(new)


def test_the_layer_rule_finds_an_upward_import():
    g = {"emaphm.models.step": {"emaphm.verdict", "emaphm.optim.de"},
         "emaphm.verdict": {"emaphm.models.step"}}
    assert upward(g) == [("emaphm.models.step", "emaphm.verdict")]


def test_the_architecture_page_names_every_package():
    """docs/architecture.md draws every package (a folder of src/emaphm) of the house."""
    text = (SRC.parents[0] / "docs" / "architecture.md").read_text(encoding="utf-8")
    packages = sorted(p.parent.relative_to(SRC / "emaphm").as_posix()
                      for p in (SRC / "emaphm").rglob("__init__.py") if p.parent != SRC / "emaphm")
    assert len(packages) >= 8
    missing = [p for p in packages if f"{p.rsplit('/', 1)[-1]}/" not in text]
    assert not missing, f"docs/architecture.md does not draw {missing}"
