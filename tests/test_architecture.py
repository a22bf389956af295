"""The import graph of the project's packages: no cycles (type-only and function-local
imports count too), and no layer importing from one above it: between the packages, and
inside auvdiag_cli from the vehicle up to the command line (see docs/architecture.md)."""

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("auvdiag_errors", "adapters", "models", "auvdiag_cli")
# What each layer may import from the project, besides itself.
ALLOWED = {"auvdiag_errors": set(), "adapters": {"auvdiag_errors"},
           "models": {"auvdiag_errors"},
           "auvdiag_cli": {"auvdiag_errors", "adapters", "models"}}


# Inside auvdiag_cli, bottom to top; a module may import from its own folder and from lower
# ranks. Modules at the package's top (errors, numeric, digest, files) are rank 0.
APPLICATION_RANKS = {"vehicle": 1, "engine": 2, "simulator": 3, "jobs": 4, "reports": 5,
                     "audit": 6, "fuzz": 6, "api": 7, "cli": 8, "__main__": 8}


def _application_layer(module: str) -> tuple[str, int]:
    parts = module.split(".")
    folder = parts[1] if len(parts) > 1 and parts[1] in APPLICATION_RANKS else "top"
    folder = "cli" if folder == "__main__" else folder
    return folder, APPLICATION_RANKS.get(folder, 0)


def _module_name(path: Path) -> str:
    parts = list(path.relative_to(ROOT).with_suffix("").parts)
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _modules() -> dict[str, Path]:
    return {_module_name(p): p for package in PACKAGES for p in (ROOT / package).rglob("*.py")}


def _imports(path: Path, known: set[str]) -> set[str]:
    """The project modules ``path`` imports, wherever the import statement stands."""
    found = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        names: list[str] = []
        if isinstance(node, ast.Import):
            names = [alias.name for alias in node.names]
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            names = [node.module, *(f"{node.module}.{a.name}" for a in node.names)]
        for name in names:
            while name and name not in known:
                name = name.rpartition(".")[0]
            if name:
                found.add(name)
    return found


def _graph() -> dict[str, set[str]]:
    modules = _modules()
    known = set(modules)
    return {name: _imports(path, known) - {name} for name, path in modules.items()}


def _cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected components of more than one module (iterative Tarjan)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    found: list[list[str]] = []
    for root in graph:
        if root in index:
            continue
        work = [(root, iter(sorted(graph[root])))]
        index[root] = low[root] = len(index)
        stack.append(root)
        on_stack.add(root)
        while work:
            node, edges = work[-1]
            advanced = False
            for target in edges:
                if target not in index:
                    index[target] = low[target] = len(index)
                    stack.append(target)
                    on_stack.add(target)
                    work.append((target, iter(sorted(graph[target]))))
                    advanced = True
                    break
                if target in on_stack:
                    low[node] = min(low[node], index[target])
            if advanced:
                continue
            work.pop()
            if work:
                low[work[-1][0]] = min(low[work[-1][0]], low[node])
            if low[node] == index[node]:
                component = []
                while True:
                    member = stack.pop()
                    on_stack.discard(member)
                    component.append(member)
                    if member == node:
                        break
                if len(component) > 1:
                    found.append(sorted(component))
    return found


def test_the_cycle_finder_finds_a_cycle():
    assert _cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]
    assert _cycles({"a": {"b"}, "b": set()}) == []


def test_no_module_imports_one_that_imports_it_back():
    assert _cycles(_graph()) == []


def test_no_layer_imports_from_a_layer_above_it():
    wrong = [f"{module} imports {target}"
             for module, targets in _graph().items() for target in targets
             if (layer := module.split(".")[0]) != (other := target.split(".")[0])
             and other not in ALLOWED[layer]]
    assert wrong == []


def test_inside_the_application_no_folder_imports_from_one_above_it():
    wrong = []
    for module, targets in _graph().items():
        if not module.startswith("auvdiag_cli"):
            continue
        folder, rank = _application_layer(module)
        for target in targets:
            if not target.startswith("auvdiag_cli"):
                continue
            other, other_rank = _application_layer(target)
            if other != folder and other_rank >= rank:
                wrong.append(f"{module} ({folder}) imports {target} ({other})")
    assert wrong == []


MODULE_LINES, FUNCTION_LINES = 400, 60


def test_modules_and_functions_stay_small():
    """Small modules with one job, functions a reader takes in at once."""
    too_long = []
    for package in PACKAGES:
        for path in (ROOT / package).rglob("*.py"):
            text = path.read_text(encoding="utf-8")
            where = path.relative_to(ROOT)
            if len(text.splitlines()) > MODULE_LINES:
                too_long.append(f"{where}: {len(text.splitlines())} lines")
            too_long += [f"{where}:{node.lineno} {node.name}: "
                         f"{node.end_lineno - node.lineno + 1} lines"
                         for node in ast.walk(ast.parse(text))
                         if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef)
                         and node.end_lineno - node.lineno + 1 > FUNCTION_LINES]
    assert too_long == []


def test_the_errors_have_one_home_that_every_module_imports_them_from():
    """No module re-exports one of `auvdiag_errors`' errors (in its ``__all__``), and the
    engine raises no command-line usage error (its own are LogError, ModelError,
    CompanionError, DerivationError)."""
    import auvdiag_errors

    errors = set(auvdiag_errors.__all__) - {"one_line"}
    for name, path in _modules().items():
        if name == "auvdiag_errors":
            continue
        tree = ast.parse(path.read_text(encoding="utf-8"))
        for node in ast.walk(tree):
            if isinstance(node, ast.Assign) and any(
                    isinstance(t, ast.Name) and t.id == "__all__" for t in node.targets):
                exported = {e.value for e in ast.walk(node.value) if isinstance(e, ast.Constant)}
                assert not exported & errors, f"{name} re-exports {exported & errors}"
        if name.startswith("auvdiag_cli.engine"):
            assert "UsageError" not in path.read_text(encoding="utf-8"), name


def test_the_diagnosis_never_reads_the_ground_truth():
    """The simulator's truth beside a log is laid against a diagnosis afterwards
    (`jobs.truth`); no engine module reads it."""
    for name, path in _modules().items():
        if name.startswith("auvdiag_cli.engine"):
            text = path.read_text(encoding="utf-8")
            assert "truth_paths" not in text and "truth_series" not in text, name


def test_the_public_module_imports_no_terminal_library():
    """A program using `auvdiag_cli.api` gets no terminal library (rich, typer, click)."""
    import subprocess
    import sys

    loaded = subprocess.run(
        [sys.executable, "-c", "import sys, auvdiag_cli.api; print(' '.join(sorted({m.split('.')"
         "[0] for m in sys.modules} & {'rich', 'typer', 'click', 'tqdm'})))"],
        capture_output=True, text=True, check=True, cwd=ROOT).stdout.split()
    assert loaded == []


def _untyped_fields(root: type) -> list[str]:
    """Fields under the dataclass ``root`` (and every dataclass its fields hold) whose type
    is or contains Any."""
    import dataclasses
    import typing

    found, seen = [], set()

    def walk(annotation: object, where: str) -> None:
        if annotation is typing.Any:
            found.append(where)
        elif isinstance(annotation, type) and dataclasses.is_dataclass(annotation):
            if annotation in seen:
                return
            seen.add(annotation)
            hints = typing.get_type_hints(annotation)
            for f in dataclasses.fields(annotation):
                walk(hints[f.name], f"{annotation.__name__}.{f.name}")
        for argument in typing.get_args(annotation):
            walk(argument, where)

    walk(root, root.__name__)
    return found


def _arguments(annotation: object) -> set[object]:
    """Every type named inside ``annotation`` (``tuple[dict[str, Any], X]`` holds Any)."""
    import typing

    found = {annotation}
    for argument in typing.get_args(annotation):
        found |= _arguments(argument)
    return found


def test_no_untyped_dict_crosses_a_layer_for_the_model_or_the_diagnosis():
    """The diagnosis and the model card are typed all the way down, and only the writers
    of model.json (train, calibrate, relate, score) touch the JSON document itself."""
    import typing
    from dataclasses import dataclass
    from typing import Any

    from auvdiag_cli import api
    from auvdiag_cli.engine.results import Diagnosis
    from auvdiag_cli.jobs.calibration_result import CalibrationResult
    from auvdiag_cli.jobs.train import TrainingResult
    from models.card import ModelCard

    @dataclass
    class Loose:
        inner: dict[str, Any]

    assert _untyped_fields(Loose) == ["Loose.inner"]        # the check sees one
    for typed in (Diagnosis, ModelCard, TrainingResult, CalibrationResult, api.AuditResult):
        assert _untyped_fields(typed) == [], typed
    # What the library's model-learning functions return is typed too. The api imports its
    # classes on first use, so its annotations resolve through its exported names.
    exported = vars(api) | {name: getattr(api, name) for name in api.__all__}
    for function in (api.relate, api.score, api.train, api.calibrate, api.audit, api.trend):
        returned = typing.get_type_hints(function, exported)["return"]
        assert Any not in _arguments(returned), function.__name__
    writers = {"auvdiag_cli.jobs.calibrate", "auvdiag_cli.jobs.relate", "auvdiag_cli.jobs.train"}
    for name, path in _modules().items():
        if name.startswith("models") or name in writers:
            continue
        tree = ast.parse(path.read_text(encoding="utf-8"))
        touched = {node.attr for node in ast.walk(tree) if isinstance(node, ast.Attribute)}
        assert not touched & {"to_document", "entry", "update_entries", "with_entries"}, name


def test_a_diagnosis_loads_no_data_frame_library_and_no_compiler_for_a_short_log(tmp_path):
    """Start-up follows what a diagnosis uses: a field log (no simulator truth beside it) is
    read, replayed and judged without pandas, a short one without numba, a DataFlash log
    without any other format's reader, and through the library without its audit, training
    or log writers."""
    import shutil
    import subprocess
    import sys

    log = shutil.copy(ROOT / "sample_logs" / "mission-large-ccw.bin", tmp_path / "dive.bin")
    unused = ["pandas", "numba", "torch", "matplotlib", "rosbags", "mcap", "adapters.rosbag",
              "adapters.rosbag1_index", "adapters.rosbag2_sqlite", "adapters.mcap",
              "adapters.ulog", "adapters.csv_log", "adapters.moos_alog", "auvdiag_cli.audit",
              "auvdiag_cli.jobs.train", "auvdiag_cli.simulator.writers"]
    loaded = subprocess.run(
        [sys.executable, "-c", "import sys; from pathlib import Path; from auvdiag_cli import "
         "api; p = api.load_profile(None); d = api.diagnose(Path(sys.argv[1]), p, "
         "api.load_model(profile=p)); print(d.verdict.value, 'adapters.mavlink' in sys.modules,"
         " ' '.join(sorted(set(sys.argv[2:]) & sys.modules.keys())))", str(log), *unused],
        capture_output=True, text=True, check=True, cwd=ROOT).stdout.split()
    assert loaded == ["normal", "True"]
