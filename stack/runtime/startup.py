"""Lockstep start-up: no module acts until every publisher's samples are known to reach every subscriber.

A lost first message would stall a lockstep run forever (its subscriber's acknowledgement never
comes), and Zenoh gives no way to ask a publisher which subscribers it knows. So each module, once
the vehicle's roster is complete (every host's supervisor has started its modules, :mod:`stack.bus.supervisors`):

1. sends probe samples on every topic it publishes (``TopicPublisher.probe``), repeatedly;
2. waits until, for every topic it subscribes to, a probe has arrived from every roster module that
   announces publishing that topic (the graph's liveliness tokens say who);
3. then registers as a lockstep member (if it is one), waits until the simulator's pre-start clocks
   reach it and it can reach the simulator's acknowledgement subscriber, declares itself synced, and
   keeps probing until every module of the roster is synced — only then does the simulator take its
   first step.

A module restarted while the stack runs joins late: the others no longer probe, so it waits until it
sees them, gives declarations a moment to settle, and joins once its session knows a subscriber for
each topic it publishes that others subscribe to.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable, Iterable, Sequence

import zenoh

from stack.bus import keys
from stack.bus.alive import AliveTokens
from stack.bus.graph import read_graph
from stack.bus.node import Node, stable_publisher_id
from stack.bus.supervisors import complete_roster, rosters
from stack.runtime.inputs import InputBuffer
from stack.runtime.lockstep import LockstepMember
from stack.runtime.spec import ModuleSpec
from stack.runtime.start_deadline import START_TIMEOUT_S, StartDeadline

log = logging.getLogger("stack.runtime")

PROBE_PERIOD_S = 0.02
LATE_JOIN_SETTLE_S = 0.5


def query_roster(node: Node, hosts: Sequence[str]) -> dict[str, int] | None:
    """The vehicle's started modules (name → pid), once every host's supervisor has started all of its own in
    this run; else None."""
    return complete_roster(rosters(node.session, node.vehicle), hosts, node.run_id)


def alive_modules(session: zenoh.Session, tokens: AliveTokens) -> dict[str, int]:
    """Modules whose alive token this session sees: name → pid."""
    alive: dict[str, int] = {}
    for reply in session.liveliness().get(keys.alive_query(tokens.vehicle), timeout=1.0):
        if reply.ok is not None and (parsed := tokens.parse(str(reply.ok.key_expr))) is not None:
            alive[parsed[0]] = parsed[1]
    return alive


def synced_modules(session: zenoh.Session, vehicle: str) -> set[str]:
    return {
        str(r.ok.key_expr).rsplit("/", 1)[-1]
        for r in session.liveliness().get(keys.synced_query(vehicle), timeout=1.0)
        if r.ok is not None
    }


def sync(
    node: Node,
    inputs: Iterable[InputBuffer],
    member: LockstepMember | None,
    spec: ModuleSpec,
    announce: Callable[[], None] | None = None,
) -> None:
    """Block until this module may take part in the lockstep (see the module docstring).

    The coordinator passes ``announce``, which sends its pre-start clocks: the members wait for them.

    A member over Zenoh in a shared-memory run (``spec.sync_with``) waits for the sync of those modules only (the
    others do not sync), and registers first: the fast path's publishers are probed for it by the coordinator's
    process (:mod:`stack.fastpath.bridge`) once it knows the member (a restarted member registers last, as any
    late joiner: its token tells the coordinator it is back). Modules outside the lockstep never probe in
    such a run (their messages are not the lockstep's), and nothing waits for them.
    """
    inputs = list(inputs)
    late_join, sync_with = spec.late_join, spec.sync_with
    registers_first = member is not None and sync_with is not None and not late_join
    deadline = StartDeadline()
    roster: dict[str, int] | None = None
    declared = False
    problem = "no supervisor roster"
    tokens = AliveTokens(node.vehicle, log.warning)
    while True:
        if roster is None:
            roster = query_roster(node, spec.hosts)
        if roster is not None:
            if announce is not None:
                announce()
            for pub in node.publishers:
                pub.probe()
            if not declared:
                # Until this module is synced no lockstep message can come (the simulator waits for
                # it), so draining takes in probes only; afterwards the trigger queue is left alone.
                for buf in inputs:
                    buf.pull()
            alive = alive_modules(node.session, tokens)
            others = {name for name in roster if name != node.name}
            probers = others - set(spec.outside) if sync_with is not None else others
            if registers_first and not member.registered:
                member.register()
            waiting_for = sorted(n for n in others if alive.get(n) != roster[n])
            if waiting_for:
                problem = f"modules not seen: {', '.join(waiting_for)}"
            elif not declared:
                if late_join:
                    time.sleep(LATE_JOIN_SETTLE_S)
                    unreached = _unmatched(node, others)
                else:
                    unreached = _unprobed(node, inputs, probers)
                if unreached:
                    problem = f"not connected yet: {', '.join(unreached)}"
                elif member is not None and not _coordinator_reachable(member, late_join):
                    problem = "the simulator's clock and this module's acknowledgements do not connect yet"
                else:
                    node.declare_token(keys.synced_token(node.vehicle, node.name))
                    declared = True
            if declared:
                syncing = others if sync_with is None else set(sync_with) - {node.name}
                pending = sorted(syncing - synced_modules(node.session, node.vehicle))
                if late_join or not pending:
                    return
                problem = f"waiting for {', '.join(pending)} to sync"
        if deadline.passed(roster is not None):
            raise RuntimeError(f"lockstep start-up timed out {START_TIMEOUT_S:.0f} s after the roster: {problem}")
        time.sleep(PROBE_PERIOD_S)


def _coordinator_reachable(member: LockstepMember, late_join: bool) -> bool:
    """Registered, hearing the coordinator's pre-start clocks (not sent any more to a late joiner), and
    able to reach its acknowledgement subscriber: no clock or acknowledgement of the run can be lost."""
    if not member.registered:
        member.register()
    member.poll_startup()
    return (late_join or member.heard_coordinator) and member.ack_reachable()


def _unmatched(node: Node, others: set[str]) -> list[str]:
    """``topic → subscriber`` pairs of a late joiner's publications whose subscribers its session does not
    know yet (a message it published now would be lost, and the lockstep would wait for its run forever)."""
    graph = read_graph(node.session, node.vehicle)
    missing = []
    for pub in node.publishers:
        entry = graph.get((pub.topic, pub.instance))
        subscribers = [s for s in entry.subscribers if s in others] if entry is not None else []
        if subscribers and not pub.matching():
            missing.append(f"{pub.topic} → {', '.join(subscribers)}")
    return missing


def _unprobed(node: Node, inputs: list[InputBuffer], others: set[str]) -> list[str]:
    """``publisher → topic`` pairs whose probe has not reached this module yet."""
    graph = read_graph(node.session, node.vehicle)
    missing = []
    for buf in inputs:
        sub = buf.sub
        entry = graph.get((sub.topic, sub.instance))
        if entry is None:
            continue
        for publisher in entry.publishers:
            if publisher in others and stable_publisher_id(node.vehicle, publisher) not in sub.probed_by:
                missing.append(f"{publisher} → {sub.topic}")
    return missing
