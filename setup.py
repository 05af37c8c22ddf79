"""Build hook: an installed stack knows the git commit it was built from.

Recordings (``stack log info``) and AUTOPILOT_VERSION name the commit of the code that ran. A source checkout
reads it from its ``.git``; an installed copy has none, so the build writes it beside the package as
``stack/COMMIT`` (see ``stack.record.provenance``). Everything else is in pyproject.toml.
"""

import subprocess
from pathlib import Path

from setuptools import setup
from setuptools.command.build_py import build_py


class BuildPyWithCommit(build_py):
    def run(self) -> None:
        super().run()
        try:
            commit = subprocess.run(
                ["git", "rev-parse", "HEAD"], cwd=Path(__file__).parent, capture_output=True, text=True, check=True
            ).stdout.strip()
        except (OSError, subprocess.CalledProcessError):
            return  # not built from a git checkout: the commit stays unknown
        target = Path(self.build_lib) / "stack" / "COMMIT"
        target.parent.mkdir(parents=True, exist_ok=True)
        target.write_text(commit + "\n")


setup(cmdclass={"build_py": BuildPyWithCommit})
