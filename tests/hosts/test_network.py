"""The hosts of tests/support/hosts.py: each a namespace of its own that reaches the others over the bridge and
nothing of the machine, cut off and reconnected at will, rate-limited in both directions, and gone after
clean-up (with every process started in it), even when set-up fails half-way."""

from __future__ import annotations

import json
import shutil
import socket
import subprocess
import sys
import time
from collections.abc import Callable, Sequence
from pathlib import Path

import pytest

from tests.support.harness import eventually
from tests.support.hosts import Host, Network, alive, namespace_pids, needs_netns, require_netns

pytestmark = needs_netns

MakeNetwork = Callable[[Sequence[str]], Network]

# Inside a host's own namespace a fixed port is free: nothing else lives there.
PORT = 5000
# Replies with the host's name to every connection.
NAME_SERVER = """
import socket, sys
server = socket.create_server(("0.0.0.0", int(sys.argv[1])))
print("ready", flush=True)
while True:
    connection, _ = server.accept()
    with connection:
        connection.sendall(sys.argv[2].encode())
"""
# Prints, as JSON, each address's reply, or the error that connecting to it met.
CLIENT = """
import json, socket, sys
timeout, port = float(sys.argv[1]), int(sys.argv[2])
replies = {}
for address in sys.argv[3:]:
    try:
        with socket.create_connection((address, port), timeout=timeout) as connection:
            replies[address] = connection.recv(100).decode()
    except OSError as e:
        replies[address] = f"{type(e).__name__}: {e}"
print(json.dumps(replies))
"""
# Counts what each connection sends until its end, and answers with the count.
SINK = """
import socket, sys
server = socket.create_server(("0.0.0.0", int(sys.argv[1])))
print("ready", flush=True)
while True:
    connection, _ = server.accept()
    with connection:
        count = 0
        while data := connection.recv(65536):
            count += len(data)
        connection.sendall(str(count).encode())
"""
# Sends SIZE bytes and prints how many arrived and the seconds from the first byte sent to the sink's answer.
SEND = """
import socket, sys, time
address, port, size = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
with socket.create_connection((address, port), timeout=30) as connection:
    start = time.monotonic()
    connection.sendall(bytes(size))
    connection.shutdown(socket.SHUT_WR)
    received = int(connection.recv(100))
    print(received, time.monotonic() - start)
"""


def serve(host: Host, script: str = NAME_SERVER) -> None:
    """Start ``script`` on ``host`` on PORT, and wait until it listens."""
    server = host.popen(sys.executable, "-c", script, str(PORT), host.name, stdout=subprocess.PIPE)
    assert server.stdout is not None
    assert server.stdout.readline() == "ready\n", f"the server on {host.name} did not start"


def replies(host: Host, *addresses: str, port: int = PORT, timeout: float = 2.0) -> dict[str, str]:
    """What a client on ``host`` gets from each of ``addresses``: a server's name, or the error met."""
    done = host.run(sys.executable, "-c", CLIENT, str(timeout), str(port), *addresses, check=True)
    return json.loads(done.stdout)


def mbit_per_s(sender: Host, receiver: Host, size: int) -> float:
    """The rate ``size`` bytes travel at from ``sender`` to the SINK on ``receiver``."""
    done = sender.run(sys.executable, "-c", SEND, receiver.address, str(PORT), str(size), check=True)
    received, seconds = done.stdout.split()
    assert int(received) == size
    return size * 8 / float(seconds) / 1e6


def test_two_hosts_reach_each_other_and_nothing_of_the_machine(network: MakeNetwork) -> None:
    net = network(["sim", "control"])
    sim, control = net.hosts["sim"], net.hosts["control"]
    assert (sim.address, control.address) == ("10.88.0.1", "10.88.0.2")
    serve(sim)
    serve(control)
    assert replies(control, sim.address) == {sim.address: "sim"}
    assert replies(sim, control.address, "127.0.0.1") == {control.address: "control", "127.0.0.1": "sim"}

    with socket.create_server(("127.0.0.1", 0)) as machine_service:
        port = machine_service.getsockname()[1]
        assert port != PORT
        reply = replies(sim, "127.0.0.1", port=port)["127.0.0.1"]
    assert reply.startswith("ConnectionRefusedError"), f"the machine's 127.0.0.1:{port} answered inside sim: {reply}"


def test_each_host_has_a_stack_home_of_its_own(network: MakeNetwork) -> None:
    net = network(["sim", "control"])
    for host in net.hosts.values():
        assert host.home.is_dir()
        done = host.run(sys.executable, "-c", "import os; print(os.environ['STACK_HOME'])", check=True)
        assert done.stdout.strip() == str(host.home)
    assert net.hosts["sim"].home != net.hosts["control"].home


def test_link_down_cuts_a_host_off_and_link_up_reconnects_it(network: MakeNetwork) -> None:
    net = network(["sim", "control"])
    sim, control = net.hosts["sim"], net.hosts["control"]
    serve(sim)
    serve(control)
    assert replies(control, sim.address) == {sim.address: "sim"}

    sim.link_down()
    cut = {**replies(control, sim.address, timeout=1.0), **replies(sim, control.address, timeout=1.0)}
    assert "sim" not in cut.values() and "control" not in cut.values(), cut

    sim.link_up()
    eventually(
        lambda: (
            replies(control, sim.address, timeout=1.0) == {sim.address: "sim"}
            and replies(sim, control.address, timeout=1.0) == {control.address: "control"}
        ),
        timeout=20,
        what="sim and control reconnected",
    )


def test_clean_up_ends_every_process_and_deletes_every_namespace(tmp_path: Path) -> None:
    require_netns()
    with Network(["sim", "control"], tmp_path, grace=0.5) as net:
        sim, control = net.hosts["sim"], net.hosts["control"]
        started = [
            sim.popen("sh", "-c", "sleep 600 & sleep 600"),  # a child the clean-up does not know of
            control.popen(  # one that ignores SIGTERM
                sys.executable, "-c",
                "import signal, time; signal.signal(signal.SIGTERM, signal.SIG_IGN); print('ready', flush=True); "
                "time.sleep(600)",
                stdout=subprocess.PIPE,
            ),
        ]  # fmt: skip
        assert started[1].stdout is not None and started[1].stdout.readline() == "ready\n"
        eventually(lambda: len(namespace_pids(sim.netns)) == 3, timeout=10, what="sh and its two sleeps running")
        pids = namespace_pids(sim.netns) + namespace_pids(control.netns)
        assert {p.pid for p in started} <= set(pids)

    assert all(p.returncode is not None for p in started)
    assert not [pid for pid in pids if alive(pid)]
    listed = subprocess.run(["ip", "netns", "list"], capture_output=True, text=True, check=True).stdout
    assert not [netns for netns in net.namespaces if netns in listed]


def test_a_set_up_failing_half_way_leaves_no_namespace_behind(tmp_path: Path) -> None:
    require_netns()
    net = Network(["sim", "bad/name"], tmp_path)
    with pytest.raises(RuntimeError, match="bad/name"), net:
        pass
    listed = subprocess.run(["ip", "netns", "list"], capture_output=True, text=True, check=True).stdout
    assert not [netns for netns in net.namespaces if netns in listed]


def test_limit_rate_holds_both_directions_under_the_limit(network: MakeNetwork) -> None:
    if shutil.which("tc") is None:
        pytest.skip("limiting a rate needs iproute2's `tc`")
    net = network(["sim", "control"])
    sim, control = net.hosts["sim"], net.hosts["control"]
    serve(sim, SINK)
    serve(control, SINK)
    size = 150_000  # 1.2 s at 1 Mbit/s
    unlimited = mbit_per_s(control, sim, size)
    assert unlimited > 10, f"{unlimited:.1f} Mbit/s without a limit: the measurement cannot tell a limit"

    control.limit_rate("1mbit")
    start = time.monotonic()
    sent, received = mbit_per_s(control, sim, size), mbit_per_s(sim, control, size)
    assert sent < 3 and received < 3, (
        f"control sends at {sent:.2f} Mbit/s, receives at {received:.2f}, limited to 1 ({unlimited:.0f} unlimited)"
    )
    assert time.monotonic() - start < 10


def test_three_hosts_on_one_bridge_all_reach_each_other(network: MakeNetwork) -> None:
    net = network(["sim", "control", "ground"])
    for host in net.hosts.values():
        serve(host)
    for host in net.hosts.values():
        others = {other.address: other.name for other in net.hosts.values() if other is not host}
        assert replies(host, *others) == others
