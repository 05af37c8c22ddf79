"""The suite's own promise (tests/conftest.py): the tests sharing a stack run on one pytest-xdist worker.

pytest-xdist groups them by a suffix on each test's id; a pytest release that stops it doing so would start a
shared stack on every worker, and the tests of one stack would run on another's.
"""

from __future__ import annotations

import os

import pytest


@pytest.fixture(scope="module")
def worker() -> str | None:
    return os.environ.get("PYTEST_XDIST_WORKER")


@pytest.mark.parametrize("test", range(4))
def test_tests_sharing_a_module_fixture_run_on_one_worker(
    worker: str | None, request: pytest.FixtureRequest, test: int
) -> None:
    if not getattr(request.config.option, "loadgroup", False):
        pytest.skip("not run by pytest-xdist's --dist loadgroup")
    assert request.node.get_closest_marker("xdist_group") is not None
    assert request.node.nodeid.endswith("@" + request.node.nodeid.split("::")[0].split("@")[0]), (
        f"pytest {pytest.__version__} with this pytest-xdist lost the groups: bound pytest in pyproject.toml"
    )
    assert worker == os.environ.get("PYTEST_XDIST_WORKER")
