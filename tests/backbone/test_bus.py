"""Publish and subscribe across real processes over Zenoh on loopback; bad input is counted and dropped."""

import contextlib
import json
import os
import socket
import subprocess
import sys
import threading

import msgspec
import pytest
import zenoh

from stack.bus import config, keys
from stack.bus.alive import AliveTokens, parse_alive_token
from stack.bus.config import BusConfig
from stack.bus.node import Node, open_session, stable_publisher_id
from stack.bus.ports import free_port
from stack.bus.topics import HEADER, MAX_SAMPLE_BYTES, RING_SAMPLES, MessageTooLarge
from stack.msg.navigation import Mission
from stack.msg.sensors import SensorGyro
from stack.runtime.startup import alive_modules
from tests.support.harness import REPO, RunningStack, chain_profile, eventually, stack_env, wait_no_processes


def test_messages_cross_processes_in_order_with_header(tmp_path):
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    out = tmp_path / "received.json"
    env = stack_env(tmp_path / "home")
    sub = subprocess.Popen(
        [sys.executable, "-m", "tests.support.peers", "sub", endpoint, "500", str(out)], env=env, cwd=REPO
    )
    pub = subprocess.Popen([sys.executable, "-m", "tests.support.peers", "pub", endpoint, "500"], env=env, cwd=REPO)
    assert pub.wait(timeout=60) == 0
    assert sub.wait(timeout=60) == 0
    got = json.loads(out.read_text())
    assert [m["param1"] for m in got] == [float(i) for i in range(500)]
    assert all(m["command"] == 400 for m in got)
    assert {m["publisher"] for m in got} == {stable_publisher_id("t1", "test_publisher")}
    seqs = [m["seq"] for m in got]
    assert seqs == sorted(seqs) and len(set(seqs)) == 500
    assert all(m["t"] == -1 for m in got)  # wall-clock publisher: not lockstep time


def run_peer(home, role: str) -> None:
    """``python -m tests.support.peers ROLE`` against the stack in ``home``, to its end."""
    out = subprocess.run([sys.executable, "-m", "tests.support.peers", role], env=stack_env(home), cwd=REPO, timeout=60)
    assert out.returncode == 0, role


def test_malformed_and_mismatched_samples_are_counted_and_dropped(tmp_path):
    home = tmp_path / "home"
    profile = chain_profile(
        tmp_path / "chain.toml", lockstep=False, extra='[[module]]\nmodule = "tests.support.modules:CommandCounter"\n'
    )
    stack = RunningStack(home, profile)
    try:
        stack.wait_up()
        run_peer(home, "rogue")

        def counter() -> dict:
            return next(m for m in stack.status()["modules"] if m["module"] == "command_counter")

        with contextlib.suppress(AssertionError):  # a heartbeat carries the counters; the assertions say what differs
            eventually(lambda: counter()["schema_errors"] >= 40, what="the counters in a heartbeat")
        assert (counter()["decode_errors"], counter()["schema_errors"]) == (20, 40)
        runs_before = counter()["runs"]
        eventually(lambda: counter()["runs"] > runs_before, what="the counter running on")
        assert counter()["state"] == "running"
        assert "schema mismatch" in stack.output and "malformed" in stack.output
    finally:
        assert stack.stop() == 0
    assert not wait_no_processes(home)


def test_malformed_alive_tokens_are_counted_and_reported_once(tmp_path):
    home = tmp_path / "home"
    profile = chain_profile(
        tmp_path / "chain.toml", lockstep=False, extra='[[module]]\nmodule = "tests.support.modules:Watcher"\n'
    )
    stack = RunningStack(home, profile)
    try:
        stack.wait_up()
        run_peer(home, "forge")
        # The well-formed token came after all the malformed ones: once it is gone they were all seen.
        stack.wait_for(r"\[watcher\].*module forge_done gone \(pid 4242\)")
        out = stack.output
        assert "Traceback" not in out and "callback error" not in out
        reports = [line for line in out.splitlines() if "malformed alive token" in line]
        assert len(reports) == 2, reports  # the supervisor's and the watcher's, once each
        assert {line.split()[0] for line in reports} == {"[stack]", "[watcher]"}
        assert "module summer alive" in out
        assert next(m for m in stack.status()["modules"] if m["module"] == "watcher")["state"] == "running"
    finally:
        assert stack.stop() == 0
    assert not wait_no_processes(home)


def test_lockstep_start_up_reads_the_alive_tokens_past_malformed_ones():
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    warnings: list[str] = []
    with (
        zenoh.open(BusConfig(listen=(endpoint,)).zenoh_config("tokens")) as tokens_session,
        zenoh.open(BusConfig(connect=(endpoint,)).zenoh_config("reader")) as reader,
    ):
        alive = "stack/t1/@alive"
        declared = [  # kept: a token lives as long as its object
            tokens_session.liveliness().declare_token(key)
            for key in (keys.alive_token("t1", "doubler", 1234), f"{alive}/summer/notanint", f"{alive}/summer")
        ]
        tokens = AliveTokens("t1", warnings.append)
        # Each reading is one query, which the malformed tokens answer again every time.
        eventually(lambda: alive_modules(reader, tokens) == {"doubler": 1234} and tokens.malformed >= 2)
        before = tokens.malformed
        assert alive_modules(reader, tokens) == {"doubler": 1234}
        assert tokens.malformed == before + 2
        del declared
    assert len(warnings) == 1 and "malformed alive token 'stack/t1/@alive/summer" in warnings[0], warnings
    assert parse_alive_token(keys.alive_token("t1", "doubler", 1234), "t1") == ("doubler", 1234)
    for key in ("stack/t1/@alive/doubler/-1", "stack/t1/@alive/doubler/0", "stack/t2/@alive/doubler/1"):
        assert parse_alive_token(key, "t1") is None


def test_a_keep_last_subscription_counts_a_burst_of_garbage_and_keeps_the_newest_valid_messages():
    """Its samples wait in Zenoh's ring, undecoded, until its owner polls or receives: a burst of garbage as long as
    the ring is counted in full, the newest valid messages are kept; ``recv`` waits for a valid one; the owner's
    thread alone takes the messages, so no other thread can wait on them."""
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    with (
        Node(BusConfig(listen=(endpoint,)), "t1", "gyro_publisher") as sender,
        Node(BusConfig(connect=(endpoint,)), "t1", "gyro_reader") as receiver,
    ):
        sub = receiver.subscriber("sensor_gyro", capacity=4, keep_last=True)
        pub = sender.publisher("sensor_gyro")
        raw = sender.session.declare_publisher(keys.topic_key("t1", "sensor_gyro", 0))
        got: list = []

        def taken_up_to(index: int) -> bool:
            got.extend(iter(sub.poll, None))
            return bool(got) and got[-1].index == index

        eventually(pub.matching, what="the subscriber known to the publisher")
        burst = RING_SAMPLES - 2
        for _ in range(burst):
            raw.put(b"\xc1")  # no stack header
        for i in range(1, 11):
            pub.publish(SensorGyro(timestamp=i, x=float(i)), now_us=i)
        eventually(lambda: taken_up_to(10), what="the burst and the gyro messages taken in")
        assert sub.schema_errors == burst and sub.received == 10
        indices = [r.index for r in got]
        assert indices == sorted(indices) and len(indices) >= 4 and indices[-4:] == [7, 8, 9, 10]
        raw.put(b"\xc1\xc1", attachment=HEADER.pack(sub.fingerprint, 7, 1, 1, 0, 0, 0))  # does not decode
        threading.Timer(0.2, lambda: pub.publish(SensorGyro(timestamp=11, x=11.0), now_us=11)).start()
        received = sub.recv()
        assert (received.index, received.msg.x, sub.decode_errors) == (11, 11.0, 1)
        with pytest.raises(TypeError, match="only a callback subscriber"):
            sub.wait(0.1)
        with pytest.raises(TypeError, match="only a callback subscriber"):
            sub.share_arrival(threading.Event())
        raw.undeclare()


def test_a_message_larger_than_the_bus_carries_is_refused_not_lost():
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    with (
        Node(BusConfig(listen=(endpoint,)), "t1", "big_publisher") as sender,
        Node(BusConfig(connect=(endpoint,)), "t1", "big_subscriber") as receiver,
    ):
        sub = receiver.subscriber("mission", capacity=16)
        pub = sender.publisher("mission")
        eventually(pub.matching, what="the subscriber known to the publisher")

        def mission(size: int) -> Mission:
            """A mission message of ``size`` bytes with the stack's header."""
            msg = Mission(mission_id=1, source="")
            msg.source = "x" * (size - HEADER.size - len(msgspec.msgpack.encode(msg)) - 2)  # str16 prefix
            assert len(msgspec.msgpack.encode(msg)) + HEADER.size == size
            return msg

        with pytest.raises(MessageTooLarge, match="mission: a message of 48001 bytes, more than the 48000"):
            pub.publish(mission(MAX_SAMPLE_BYTES + 1), now_us=1)
        pub.publish(mission(MAX_SAMPLE_BYTES), now_us=2)
        got: list = []
        eventually(lambda: got.append(sub.poll()) or any(got), what="the largest message the bus carries")
        first = next(r for r in got if r is not None)
        msg, index = first.msg, first.index
        assert len(msg.source) > 47_000 and index == 1  # the refused one was not counted: no gap


def test_a_routers_zenoh_runtime_has_a_worker_for_each_link_to_another_router(monkeypatch):
    """Zenoh's defaults without such links; the setting is the process's only while its first session opens (what
    Zenoh reads), and a user's own ZENOH_RUNTIME is kept."""
    seen: list[str | None] = []
    monkeypatch.setattr(config.zenoh, "open", lambda conf: seen.append(os.environ.get("ZENOH_RUNTIME")))
    monkeypatch.delenv("ZENOH_RUNTIME", raising=False)
    router = BusConfig(mode="router")
    config.open_router(router, "router", links=2)
    config.open_router(router, "router", links=0)
    assert seen == ["(rx: (worker_threads: 4), tx: (worker_threads: 3))", None]
    assert "ZENOH_RUNTIME" not in os.environ
    monkeypatch.setenv("ZENOH_RUNTIME", "(rx: (worker_threads: 3))")
    config.open_router(router, "router", links=2)
    assert seen[-1] == os.environ["ZENOH_RUNTIME"] == "(rx: (worker_threads: 3))"


def test_a_module_whose_port_was_taken_connects_to_the_modules_started_after_it():
    """Peers reach each other only over links of their own (the router relays nothing between two peers): a module
    that found its endpoint taken listens elsewhere, so the modules started after it, connecting to the endpoint it
    was given, miss it; it connects to them itself."""
    router_ep, later_ep = (f"tcp/127.0.0.1:{free_port()}" for _ in range(2))
    taken = socket.socket(socket.AF_INET, socket.SOCK_STREAM)  # another process's listener on the module's port
    taken.bind(("127.0.0.1", 0))
    taken.listen()
    own = f"tcp/127.0.0.1:{taken.getsockname()[1]}"
    router = zenoh.open(BusConfig(mode="router", listen=(router_ep,)).zenoh_config("router"))
    moved = open_session(BusConfig(connect=(router_ep,), listen=(own,), mesh=(own, later_ep)), "moved")
    later = open_session(BusConfig(connect=(router_ep, own), listen=(later_ep,), mesh=(own, later_ep)), "later")
    heard: dict[str, int] = {"moved": 0, "later": 0}
    subs = [
        moved.declare_subscriber("test/to_moved", lambda _: heard.__setitem__("moved", heard["moved"] + 1)),
        later.declare_subscriber("test/to_later", lambda _: heard.__setitem__("later", heard["later"] + 1)),
    ]
    pubs = [later.declare_publisher("test/to_moved"), moved.declare_publisher("test/to_later")]
    try:

        def both_heard() -> bool:
            for pub in pubs:
                pub.put(b"x")
            return heard["moved"] > 0 and heard["later"] > 0

        eventually(both_heard, timeout=20.0, what="messages both ways between the moved module and a later one")
    finally:
        for entity in (*subs, *pubs):
            entity.undeclare()
        taken.close()  # first: a session closes only once its handshake with that listener has failed
        for session in (later, moved, router):
            session.close()
