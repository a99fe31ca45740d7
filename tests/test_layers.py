"""The import graph keeps its layers: no cycles, not even through imports inside functions, and
dependencies point one way.

    cli (omninoise, farms)  ->  backend (core: wave, neural, solid, bakes, job files)  ->  export (file writers)
    blender_addon           ->  backend
    training (torch)        ->  backend

Read statically from the source (every ``import`` anywhere in a module, function bodies included), so a cycle
held together by a function-level import counts, and nothing needs torch or bpy to run this test.
"""
import ast
import os
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
PACKAGES = ("backend", "export", "blender_addon", "cli", "training")
#: the modules at the package's root (the extension's entry points and the Python API)
ROOT_MODULES = ("__init__.py", "__main__.py", "api.py")


def modules() -> dict:
    """{dotted module name: file path} of every module of the package ``omninoise`` (the repository root)."""
    out = {}
    for f in ROOT_MODULES:
        out["omninoise" if f == "__init__.py" else "omninoise." + f[:-3]] = os.path.join(ROOT, f)
    for top in PACKAGES:
        for folder, _, files in os.walk(os.path.join(ROOT, top)):
            for f in files:
                if f.endswith(".py"):
                    path = os.path.join(folder, f)
                    name = "omninoise." + os.path.relpath(path, ROOT)[:-3].replace(os.sep, ".")
                    out[name[: -len(".__init__")] if name.endswith(".__init__") else name] = path
    return out


def layer(name: str) -> str:
    """The layer of a dotted name: ``omninoise.backend.bake`` -> ``backend``; outside names as their top."""
    parts = name.split(".")
    return parts[1] if parts[0] == "omninoise" and len(parts) > 1 else parts[0]

def imports(name: str, path: str, known: dict) -> dict:
    """{imported name: line} of one module: project modules resolved to their dotted names, others as written
    (``torch``, ``bpy.types`` ...)."""
    package = name if path.endswith("__init__.py") else name.rpartition(".")[0]
    with open(path, encoding="utf-8") as fh:
        tree = ast.parse(fh.read(), path)
    out = {}
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for a in node.names:
                out.setdefault(a.name, node.lineno)
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                parts = package.split(".")
                base = ".".join(parts[: len(parts) - node.level + 1] + ([node.module] if node.module else []))
            else:
                base = node.module or ""
            for a in node.names:
                full = f"{base}.{a.name}"
                out.setdefault(full if full in known else base, node.lineno)
    return out

def graph() -> tuple:
    known = modules()
    edges = {m: imports(m, p, known) for m, p in known.items()}
    return known, edges

def cycles(edges: dict, known: dict) -> list:
    """Strongly connected components with more than one module (Tarjan), each sorted."""
    adj = {m: [d for d in deps if d in known and d != m] for m, deps in edges.items()}
    index, low, stack, on, out, counter = {}, {}, [], set(), [], [0]

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in adj[v]:
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(sorted(comp))

    for v in sorted(adj):
        if v not in index:
            visit(v)
    return out

def test_no_import_cycles():
    known, edges = graph()
    found = cycles(edges, known)
    detail = [" <-> ".join(c) + ": " + "; ".join(f"{m} imports {d} (line {edges[m][d]})" for m in c
                                                  for d in edges[m] if d in c) for c in found]
    assert not found, "\n".join(detail)

def test_the_cycle_finder_finds_a_cycle_through_a_function_level_import(tmp_path):
    """The instrument itself: two modules that import each other, one of them inside a function."""
    (tmp_path / "a.py").write_text("from . import b\n")
    (tmp_path / "b.py").write_text("def f():\n    from .a import x\n")
    known = {"pkg.a": str(tmp_path / "a.py"), "pkg.b": str(tmp_path / "b.py")}
    edges = {m: imports(m, p, known) for m, p in known.items()}
    assert cycles(edges, known) == [["pkg.a", "pkg.b"]]

def test_dependencies_point_one_way():
    known, edges = graph()
    bad = []
    for m, deps in edges.items():
        lm = layer(m)
        runtime = lm in ("backend", "export")
        for d, line in deps.items():
            ld = layer(d)
            where = f"{m} (line {line}) imports {d}"
            if ld == "bpy" and lm != "blender_addon":
                bad.append(where + ": only blender_addon may import bpy")
            if runtime and ld in ("training", "torch", "onnx"):
                bad.append(where + ": the runtime never imports training code or torch")
            if lm in ("backend", "export", "blender_addon", "training", "api") and ld == "cli":
                bad.append(where + ": nothing below the command line imports it")
            if lm in ("blender_addon", "api") and ld == "training":
                bad.append(where + ": the add-on and the API never import training code")
            if lm == "export" and ld in ("backend", "blender_addon"):
                bad.append(where + ": the file writers sit below the engines")
            if ld in ("dask", "distributed") and m != "omninoise.cli.farm":
                bad.append(where + ": only cli/farm.py uses Dask (an optional extra)")
            if lm in ("backend", "api") and ld == "blender_addon":
                bad.append(where + ": the core and the API never import the Blender layer")
            if lm in ("backend", "export", "blender_addon") and layer(d) != d.split(".")[0] and \
                    not m.endswith("__init__") and line and _absolute(known[m], line):
                bad.append(where + ": the extension's packages import each other relatively (inside Blender the "
                                   "package is bl_ext.<repository>.omninoise)")
    assert not bad, "\n".join(bad)


def _absolute(path: str, line: int) -> bool:
    """Whether the import statement on ``line`` of ``path`` names ``omninoise`` absolutely."""
    with open(path, encoding="utf-8") as fh:
        text = fh.read().splitlines()[line - 1].strip()
    return text.startswith(("from omninoise", "import omninoise"))


def test_nothing_imports_the_old_top_level_names():
    """Every module, test, bench and tool reaches the code as ``omninoise.<layer>``: a bare ``import backend``
    would load a second copy of the engines under another name."""
    import re
    import subprocess

    files = subprocess.run(["git", "ls-files", "*.py"], cwd=ROOT, capture_output=True, text=True).stdout.split()
    pat = re.compile(r"^\s*(from|import) (%s)\b" % "|".join(PACKAGES))
    bad = []
    for f in files:
        with open(os.path.join(ROOT, f), encoding="utf-8") as fh:
            bad += [f"{f}:{n}: {ln.strip()}" for n, ln in enumerate(fh, 1) if pat.match(ln)]
    assert not bad, "\n".join(bad)


def test_files_are_replaced_only_by_the_atomic_helper():
    """One atomic-write helper (export/atomic.py: fsync, stale-temporary clean-up): no other module renames a
    hand-written temporary file onto its result."""
    known, _ = graph()
    bad = []
    for name, path in known.items():
        if name == "omninoise.export.atomic":
            continue
        with open(path, encoding="utf-8") as fh:
            for n, line in enumerate(fh, 1):
                if "os.replace(" in line or "os.rename(" in line:
                    bad.append(f"{name}:{n}: {line.strip()}")
    assert not bad, "\n".join(bad)

#: the test files that exercise training and evaluation (training, torch); every other test file must run
#: without torch (the runtime's tests use tests/data/tiny_* and the shipped models)
TORCH_TEST_FILES = {"test_conv_generator.py", "test_neural_deep.py", "test_neural_eval.py", "test_neural_int8.py",
                    "test_neural_runtime.py", "test_neural_training.py", "test_solid_card.py",
                    "test_solid_eval.py", "test_solid_harmonics_tool.py", "test_solid_model.py",
                    "test_solid_morphology.py", "test_solid_morphology_loss.py", "test_solid_photos.py",
                    "test_solid_spectrum.py", "test_structure_features.py", "test_training_line.py", "test_zoo.py",
                    "test_zoo_blender.py"}

def test_only_training_and_evaluation_tests_need_torch(tmp_path):
    import re
    import subprocess

    blocker = tmp_path / "torch"
    blocker.mkdir()
    (blocker / "__init__.py").write_text('raise ModuleNotFoundError("No module named torch (blocked)", name="torch")\n')
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(filter(None, [str(tmp_path), os.environ.get("PYTHONPATH")])))
    tests = os.path.dirname(os.path.abspath(__file__))
    r = subprocess.run([sys.executable, "-m", "pytest", "--co", "-q", "-rs", "-p", "no:cacheprovider", tests],
                       capture_output=True, text=True, env=env, cwd=os.path.dirname(tests))
    assert r.returncode == 0, r.stdout[-2000:] + r.stderr[-2000:]
    skipped = {m.group(1) for m in re.finditer(r"SKIPPED \[\d+\] \S*?(test_\w+\.py):\d+: could not import 'torch'",
                                                r.stdout)}
    assert skipped == TORCH_TEST_FILES, (sorted(skipped - TORCH_TEST_FILES), sorted(TORCH_TEST_FILES - skipped))


def test_modules_import_only_public_names_from_each_other():
    """Public names only across modules: no ``from .x import _private`` in the project."""
    bad = []
    for name, path in modules().items():
        with open(path, encoding="utf-8") as fh:
            tree = ast.parse(fh.read(), path)
        for node in ast.walk(tree):
            if isinstance(node, ast.ImportFrom) and (node.level or (node.module or "").split(".")[0] in PACKAGES):
                bad += [f"{name} (line {node.lineno}) imports {a.name} from {node.module or '.'}"
                        for a in node.names if a.name.startswith("_") and not a.name.startswith("__")]
    assert not bad, "\n".join(bad)
