"""What `pip install .` installs: the package with the commit it was built from, the launch files beside it."""

import subprocess
import sys
import zipfile

from stack.record.provenance import git_commit
from tests.support.harness import REPO


def test_a_built_wheel_knows_its_commit_and_carries_the_launch_files(tmp_path):
    out = subprocess.run(
        [sys.executable, "-m", "pip", "wheel", "--no-deps", "-q", str(REPO), "-w", str(tmp_path)],
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert out.returncode == 0, out.stderr
    (wheel,) = tmp_path.glob("stack-*.whl")
    with zipfile.ZipFile(wheel) as built:
        names = set(built.namelist())
        assert built.read("stack/COMMIT").decode().strip() == git_commit()
    data = {n.split(".data/data/", 1)[1] for n in names if ".data/data/" in n}
    assert {"share/stack/launch/sitl_quad.toml", "share/stack/launch/missions/box.plan"} <= data
