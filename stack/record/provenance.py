"""Where a recording came from: the git commit of the stack's source tree, read without running git, or, for an
installed copy, the commit its build wrote beside the package (``COMMIT``, see setup.py)."""

from __future__ import annotations

import re
from pathlib import Path

import stack

SOURCE_ROOT = Path(stack.__file__).resolve().parents[1]
BUILT_COMMIT = Path(stack.__file__).resolve().parent / "COMMIT"
_SHA = re.compile(r"^[0-9a-f]{40}([0-9a-f]{24})?$")


def git_commit(root: Path = SOURCE_ROOT, built: Path = BUILT_COMMIT) -> str:
    """The commit checked out in ``root`` (a 40-hex sha); else the one an installed copy was ``built`` from;
    else ""."""
    return _checked_out(root) or _built_from(built)


def _built_from(built: Path) -> str:
    try:
        sha = built.read_text().strip()
    except OSError:
        return ""
    return sha if _SHA.match(sha) else ""


def _checked_out(root: Path) -> str:
    git = root / ".git"
    try:
        if git.is_file():  # a worktree or submodule: "gitdir: <path>"
            text = git.read_text().strip()
            if not text.startswith("gitdir:"):
                return ""
            git = (root / text.removeprefix("gitdir:").strip()).resolve()
        head = (git / "HEAD").read_text().strip()
        if _SHA.match(head):
            return head
        if not head.startswith("ref:"):
            return ""
        ref = head.removeprefix("ref:").strip()
        common = git
        commondir = git / "commondir"
        if commondir.is_file():
            common = (git / commondir.read_text().strip()).resolve()
        for base in (git, common):
            loose = base / ref
            if loose.is_file():
                sha = loose.read_text().strip()
                return sha if _SHA.match(sha) else ""
        packed = common / "packed-refs"
        if packed.is_file():
            for line in packed.read_text().splitlines():
                sha, _, name = line.partition(" ")
                if name == ref and _SHA.match(sha):
                    return sha
    except OSError:
        return ""
    return ""
