"""A real-time run pulls a module's queued inputs (commands) before its latest-value inputs, so a command sent on
seeing an input (MISSION_START on a mission_result) is never judged without it."""

from __future__ import annotations

from stack.bus.topics import Received
from stack.runtime.inputs import InputBuffer
from stack.runtime.runner import Runtime


class _Sub:
    def __init__(self, arrivals: list[object]) -> None:
        self.arrivals = arrivals

    def poll(self):
        return self.arrivals.pop(0) if self.arrivals else None


def test_queues_are_pulled_before_latest_values():
    runtime = Runtime.__new__(Runtime)
    status, result, command, trigger = (InputBuffer(_Sub([]), queue) for queue in (False, False, True, False))
    runtime.inputs = {("status", 0): status, ("mission_result", 0): result, ("command", 0): command, ("t", 0): trigger}
    runtime._trigger_buf = trigger
    assert runtime._wall_inputs() == [command, status, result]


def test_an_input_that_arrives_during_the_pulls_is_seen_with_the_command_it_caused():
    """The mission_result arrives, then the command sent on it, both while the run is pulling its inputs: with
    the queue pulled first, a command that is seen always finds the result."""
    result_arrivals: list[object] = []
    command_arrivals: list[object] = []
    result = InputBuffer(_Sub(result_arrivals), False)
    command = InputBuffer(_Sub(command_arrivals), True)
    runtime = Runtime.__new__(Runtime)
    runtime.inputs = {("mission_result", 0): result, ("vehicle_command", 0): command}
    runtime._trigger_buf = None
    order = runtime._wall_inputs()
    # Both arrive after the first pull of this run: the command waits for the next run, with its result.
    order[0].pull()
    result_arrivals.append(Received(0, 1, 1, "result", 1))
    command_arrivals.append(Received(0, 2, 1, "MISSION_START", 1))
    order[1].pull()
    for buf in order:
        buf.promote_all()
    assert command.take() == [] and result.latest == "result"
    for buf in order:
        buf.pull()
        buf.promote_all()
    assert command.take() == ["MISSION_START"] and result.latest == "result"
