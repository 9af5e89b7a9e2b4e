"""dvc.yaml's deps cover the code each stage runs: every hexpipe module its CLI command imports, transitively."""

import ast
from pathlib import Path

import pytest
import yaml

ROOT = Path(__file__).resolve().parents[1]
CLI = ROOT / "hexpipe" / "cli.py"
HELPERS = ("load", "writable")  # cli.py functions every stage command calls (user_errors only names error classes)


def module_file(name: str) -> Path | None:
    base = ROOT / name.replace(".", "/")
    for path in (base.with_suffix(".py"), base / "__init__.py"):
        if path.is_file():
            return path
    return None


def imported(tree: ast.AST) -> set[str]:
    """hexpipe modules imported anywhere in `tree` (function bodies too: they run when called), with their
    parent packages (whose __init__ runs first)."""
    out: set[str] = set()
    for node in ast.walk(tree):  # first: typing-only imports never run
        if isinstance(node, ast.If) and getattr(node.test, "id", "") == "TYPE_CHECKING":
            node.body = []
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and node.module and node.module.startswith("hexpipe"):
            out.add(node.module)
            out |= {f"{node.module}.{a.name}" for a in node.names if module_file(f"{node.module}.{a.name}")}
        elif isinstance(node, ast.Import):
            out |= {a.name for a in node.names if a.name.startswith("hexpipe")}
    return out | {".".join(m.split(".")[:i]) for m in out for i in range(1, m.count(".") + 1)}


def closure(starts: set[str]) -> set[Path]:
    seen: set[str] = set()
    todo = list(starts)
    while todo:
        name = todo.pop()
        path = module_file(name)
        if name in seen or name == "hexpipe.cli" or path is None:
            continue
        seen.add(name)
        tree = ast.parse(path.read_text())
        if path.name == "__init__.py":  # a package's facade: only its top level runs on import (hexpipe.load_policy
            tree.body = [n for n in tree.body if not isinstance(n, ast.FunctionDef)]  # is not a stage's code)
        todo += imported(tree)
    return {module_file(m).relative_to(ROOT) for m in seen} | {CLI.relative_to(ROOT)}


def command_imports(stage: str) -> set[str]:
    """What `hexpipe <stage>` imports: cli.py's top level, the command's body and the helpers it calls."""
    tree = ast.parse(CLI.read_text())
    top = imported(ast.Module([n for n in tree.body if isinstance(n, ast.Import | ast.ImportFrom)], []))
    functions = {f.name: f for f in tree.body if isinstance(f, ast.FunctionDef)}
    for f in functions.values():
        for deco in f.decorator_list:
            named = [a.value for a in getattr(deco, "args", []) if isinstance(a, ast.Constant)]
            if "command" in ast.unparse(deco) and (named or [f.name.replace("_", "-")])[0] == stage:
                return top | imported(f) | {m for h in HELPERS for m in imported(functions[h])}
    raise AssertionError(f"no command {stage!r} in cli.py")


STAGES = yaml.safe_load((ROOT / "dvc.yaml").read_text())["stages"]


@pytest.mark.parametrize("stage", sorted(STAGES))
def test_every_module_a_stage_runs_is_a_dep(stage: str) -> None:
    command = STAGES[stage]["cmd"].split()
    assert command[0] == "hexpipe"
    deps = [Path(d) for d in STAGES[stage]["deps"]]
    code = closure(command_imports(command[1]))
    assert Path("hexpipe/sim/terrain/model.py") in code or stage == "train-vae"  # the walk reaches sub-packages
    missing = sorted(str(p) for p in code if not any(p == d or d in p.parents for d in deps))
    assert not missing, f"dvc.yaml stage {stage} runs these modules but does not list them: {missing}"


def test_an_interrupted_repro_keeps_every_report_file() -> None:
    """`dvc repro` deletes a stage's outputs before running it unless they persist: a report file (git-tracked,
    `cache: false`, written atomically by its stage) must persist, so that a stage stopped half-way leaves the
    last report, not none. Folders (dvclive's plots, written row by row) and the cached data folders are exempt."""
    files = []
    for name, stage in STAGES.items():
        for kind in ("outs", "metrics", "plots"):
            for entry in stage.get(kind, []):
                path, flags = next(iter(entry.items())) if isinstance(entry, dict) else (entry, {})
                if flags.get("cache") is False and Path(path).suffix:
                    files.append((name, path, flags.get("persist", False)))
    assert len(files) >= 12, files  # every stage's metrics, speed and the evaluation's tables, report and summary
    missing = [f"{stage}: {path}" for stage, path, persist in files if not persist]
    assert not missing, f"report files a stopped repro would delete (add persist: true): {missing}"
