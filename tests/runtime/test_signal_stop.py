"""A SIGTERM that lands inside threading's lock code is still a clean stop, not a crash."""

import io
import logging
import threading

import pytest

from stack.runtime import main as module_main
from stack.runtime.runner import Shutdown, shutdown_behind
from stack.runtime.spec import ModuleSpec


def lock_code_failing_while_unwinding() -> RuntimeError:
    """What ``Condition.wait`` raises when the signal handler's Shutdown interrupts its re-acquire."""
    lock = threading.Lock()
    try:
        try:
            raise Shutdown("SIGTERM")
        finally:
            lock.release()  # the lock was never re-acquired
    except RuntimeError as e:
        return e
    raise AssertionError("releasing an unlocked lock did not fail")


def test_the_shutdown_behind_an_error_is_found_through_its_context():
    error = lock_code_failing_while_unwinding()
    assert "release unlocked lock" in str(error)
    assert str(shutdown_behind(error)) == "SIGTERM"
    assert shutdown_behind(RuntimeError("a real fault")) is None
    assert shutdown_behind(ValueError("bad")) is None


@pytest.mark.parametrize(
    ("raised", "code", "logged"),
    [
        (lock_code_failing_while_unwinding, 0, "stopped (SIGTERM)"),
        (lambda: RuntimeError("a real fault"), 1, "crashed"),
        (lambda: ValueError("bad argument"), 1, "bad argument"),
    ],
)
def test_a_module_process_tells_a_stop_from_a_crash(tmp_path, monkeypatch, caplog, raised, code, logged):
    class FailingRuntime:
        def __init__(self, spec: ModuleSpec) -> None:
            pass

        def run(self) -> None:
            raise raised()

    spec = tmp_path / "spec.json"
    spec.write_text(ModuleSpec(name="tick_source", module="tests.support.modules:TickSource").to_json())
    monkeypatch.setattr(module_main, "Runtime", FailingRuntime)
    monkeypatch.setattr("signal.signal", lambda sig, handler: None)  # the test process keeps its own handlers
    monkeypatch.setattr("sys.stdin", io.TextIOWrapper(io.BytesIO(b"go\n")))
    with caplog.at_level(logging.INFO):
        assert module_main.main([str(spec)]) == code
    assert logged in caplog.text
