"""Keeping idle CPUs awake while a lockstep run goes as fast as it can.

In lockstep a step passes from module process to module process, each sleeping in poll() until the one
before it publishes; every hop wakes a process, and when its CPU is idle the CPU has to wake first. A CPU
that halts when idle, as a virtual machine's vCPU does (a KVM guest's ``haltpoll`` cpuidle driver, a
Firecracker microVM), takes tens of microseconds to come back, several times a step
(``benchmarks/bench_lockstep.py`` measures the round trip both ways).

Linux's PM QoS interface lets a program cap the exit latency of the idle states the CPUs may enter: write a
32-bit count of microseconds to ``/dev/cpu_dma_latency`` and keep the file open; the request holds until the
file is closed, by the program or by the kernel when the program dies (``Documentation/power/pm_qos_interface.rst``;
rt-tests' ``cyclictest`` holds 0 the same way). At 0 an idle CPU polls instead of sleeping, so a woken
process runs at once. That spends the idle CPUs' power, so only a lockstep run that goes as fast as it can
(``stack fly``, ``stack up --speed max``), which keeps the CPUs busy anyway, asks for it. The device belongs
to root (a udev rule can grant it to a group); without it the run goes as it is.
"""

from __future__ import annotations

import os
import struct

CPU_LATENCY_DEVICE = "/dev/cpu_dma_latency"


class AwakeCpus:
    """A PM QoS request that idle CPUs wake within ``latency_us`` (0: they do not sleep) until :meth:`close`.

    ``held`` says whether the kernel took it; ``refusal`` why not (the device missing or not allowed)."""

    def __init__(self, latency_us: int = 0, device: str = CPU_LATENCY_DEVICE) -> None:
        self._fd = -1
        self.refusal = ""
        try:
            self._fd = os.open(device, os.O_WRONLY)
            os.write(self._fd, struct.pack("=i", latency_us))
        except OSError as e:
            self.close()
            self.refusal = f"{device}: {e.strerror or e}"

    @property
    def held(self) -> bool:
        return self._fd >= 0

    def close(self) -> None:
        if self._fd >= 0:
            os.close(self._fd)
            self._fd = -1
