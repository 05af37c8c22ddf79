"""Every package the code imports is declared in pyproject.toml, by itself, not through another package.

A package that only comes along with another one (click with typer before 0.26, pyarrow with rerun-sdk)
is gone the day that one stops needing it, and with it every test that imports it. The stack's code may
import what ``dependencies`` declares; the tests and benchmarks also what the ``test`` extra declares.
"""

from __future__ import annotations

import ast
import importlib.metadata
import re
import sys
import tomllib
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
PROJECT = tomllib.loads((REPO / "pyproject.toml").read_text())["project"]
OWN = {"stack", "tests"}


def distribution_name(requirement: str) -> str:
    """PEP 503's normal form of a requirement's distribution name."""
    match = re.match(r"[A-Za-z0-9._-]+", requirement)
    assert match, requirement
    return re.sub(r"[-_.]+", "-", match.group(0)).lower()


RUNTIME = {distribution_name(r) for r in PROJECT["dependencies"]}
TEST = RUNTIME | {distribution_name(r) for r in PROJECT["optional-dependencies"]["test"]}


def imported_packages(root: Path) -> dict[str, Path]:
    """The top-level packages the files under ``root`` import (one file that imports each), leaving out the
    standard library, the project's own packages and modules beside the file."""
    found: dict[str, Path] = {}
    for path in sorted(root.rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text(), str(path))):
            if isinstance(node, ast.Import):
                names = [alias.name for alias in node.names]
            elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
                names = [node.module]
            else:
                continue
            for name in names:
                top = name.split(".")[0]
                local = (path.parent / f"{top}.py").exists() or (path.parent / top).is_dir()
                if top not in sys.stdlib_module_names and top not in OWN and not local:
                    found.setdefault(top, path)
    return found


PROVIDERS = importlib.metadata.packages_distributions()


@pytest.mark.parametrize(("directory", "declared"), [("stack", RUNTIME), ("tests", TEST), ("benchmarks", TEST)])
def test_every_imported_package_is_declared(directory: str, declared: set[str]) -> None:
    undeclared = []
    for package, path in imported_packages(REPO / directory).items():
        providers = {distribution_name(d) for d in PROVIDERS.get(package, [])}
        if not providers & declared:
            where = f"provided by {', '.join(sorted(providers))}" if providers else "not installed"
            undeclared.append(f"{package} ({where}), imported by {path.relative_to(REPO)}")
    assert not undeclared, "imported but not declared in pyproject.toml: " + "; ".join(undeclared)
