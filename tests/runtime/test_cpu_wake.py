"""The PM QoS request that keeps idle CPUs awake (stack.runtime.cpu_wake): held while open, gone once closed.

The kernel holds the least of every process's requests, and tests run side by side, so a test tells its own
request by the open file, not by the latency left once it is closed."""

import os
import struct
from pathlib import Path

import pytest

from stack.runtime.cpu_wake import CPU_LATENCY_DEVICE, AwakeCpus
from tests.support.harness import RunningStack, chain_profile, wait_no_processes

needs_device = pytest.mark.skipif(
    not os.access(CPU_LATENCY_DEVICE, os.R_OK | os.W_OK), reason=f"{CPU_LATENCY_DEVICE} needs root (or a udev rule)"
)


def cpu_latency_us() -> int:
    """The latency the kernel currently holds idle CPUs to: the least of all the requests."""
    fd = os.open(CPU_LATENCY_DEVICE, os.O_RDONLY)
    try:
        return struct.unpack("=i", os.read(fd, 4))[0]
    finally:
        os.close(fd)


def holds_request(pid: int | str) -> bool:
    fds = Path(f"/proc/{pid}/fd")
    return any(os.path.realpath(fds / fd) == CPU_LATENCY_DEVICE for fd in os.listdir(fds))


def test_a_request_writes_its_latency_and_a_refused_one_says_why(tmp_path):
    device = tmp_path / "device"
    device.write_bytes(b"")
    awake = AwakeCpus(latency_us=7, device=str(device))
    assert awake.held and awake.refusal == ""
    awake.close()
    awake.close()
    assert not awake.held and struct.unpack("=i", device.read_bytes()) == (7,)
    missing = AwakeCpus(device=str(tmp_path / "none"))
    assert not missing.held and "No such file" in missing.refusal


@needs_device
def test_the_kernel_holds_the_request_until_it_is_closed():
    awake = AwakeCpus()
    try:
        assert holds_request("self") and cpu_latency_us() == 0
    finally:
        awake.close()
    assert not holds_request("self")


@needs_device
@pytest.mark.parametrize("speed, awake", [("max", True), ("2", False)])
def test_only_a_lockstep_run_as_fast_as_it_can_keeps_the_cpus_awake(tmp_path, speed, awake):
    home = tmp_path / "home"
    stack = RunningStack(home, chain_profile(tmp_path / "chain.toml"), "--speed", speed)
    try:
        stack.wait_up()
        assert holds_request(stack.proc.pid) == awake
        if awake:
            assert cpu_latency_us() == 0
        assert ("idle CPUs kept awake for the run" in stack.output) == awake, stack.output
        assert stack.stop() == 0, stack.output
    finally:
        stack.kill()
    assert not wait_no_processes(home)
